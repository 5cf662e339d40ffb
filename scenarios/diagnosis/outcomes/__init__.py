"""Outcome evidence (overturned or not): the ensembles' probabilities, their proper scores, the baselines and the
outcome diagnosis' result."""

from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import diagnose_outcomes
from housner.scenarios.diagnosis.outcomes.outcome_results import OutcomeDiagnosis

__all__ = ["OutcomeDiagnosis", "diagnose_outcomes"]
