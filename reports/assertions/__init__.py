"""Tolerance assertions for users' pytest: CDF, record-by-record and fragility agreement."""

from housner.reports.assertions.runs import (
    AgreementReport,
    CDFAgreementError,
    Criterion,
    RecordAgreementError,
    assert_cdf_agreement,
    assert_record_agreement,
)
from housner.reports.assertions.studies import FragilityAgreementError, assert_fragility_agreement

__all__ = [
    "AgreementReport",
    "CDFAgreementError",
    "Criterion",
    "FragilityAgreementError",
    "RecordAgreementError",
    "assert_cdf_agreement",
    "assert_fragility_agreement",
    "assert_record_agreement",
]
