"""A model against a campaign's records: the time-history error, the localisation of the misfit and the
physical classes it points to."""

from housner.scenarios.diagnosis.comparison.record_comparison import compare

__all__ = ["compare"]
