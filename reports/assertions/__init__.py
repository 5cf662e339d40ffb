"""Tolerance assertions for users' pytest: an engine's one verdict, CDF, record-by-record and fragility agreement.

The criteria and the report of them are :mod:`housner.reports.assertions.criteria`'s; ``load_results``
(a run directory's results table) is :func:`housner.scenarios.execution.rundir.load_results`.
"""

from housner.reports.assertions.criteria import AgreementReport, CDFAgreementError, Criterion, RecordAgreementError
from housner.reports.assertions.runs import assert_cdf_agreement, assert_record_agreement
from housner.reports.assertions.studies import FragilityAgreementError, assert_fragility_agreement
from housner.reports.assertions.verdict import VerdictError, assert_verdict
from housner.scenarios.execution.rundir import load_results

__all__ = [
    "AgreementReport",
    "CDFAgreementError",
    "Criterion",
    "FragilityAgreementError",
    "RecordAgreementError",
    "VerdictError",
    "assert_cdf_agreement",
    "assert_fragility_agreement",
    "assert_record_agreement",
    "assert_verdict",
    "load_results",
]
