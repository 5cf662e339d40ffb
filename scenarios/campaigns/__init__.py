"""Measured campaigns: reading them, comparing a model with them, locating the misfit, diagnosis and verdict;
outcome records (overturned or not) and their diagnosis; the importer of the ASU granite shake-table tests."""

from housner.scenarios.campaigns.asu import import_asu
from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.campaigns.compare import compare
from housner.scenarios.campaigns.diagnose import diagnose
from housner.scenarios.campaigns.outcome_results import OutcomeDiagnosis
from housner.scenarios.campaigns.outcomes import diagnose_outcomes
from housner.scenarios.campaigns.records import OutcomeRecord
from housner.scenarios.campaigns.results import Diagnosis

__all__ = [
    "Campaign",
    "Diagnosis",
    "OutcomeDiagnosis",
    "OutcomeRecord",
    "compare",
    "diagnose",
    "diagnose_outcomes",
    "import_asu",
    "load_campaign",
]
