"""Measured campaigns: reading them, comparing a model with them, locating the misfit, diagnosis and verdict."""

from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.campaigns.compare import compare
from housner.scenarios.campaigns.diagnose import diagnose
from housner.scenarios.campaigns.results import Diagnosis

__all__ = ["Campaign", "Diagnosis", "compare", "diagnose", "load_campaign"]
