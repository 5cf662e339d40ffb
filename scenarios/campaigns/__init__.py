"""Measured campaigns: the format, its reader, the records (theta histories or outcomes), the sensor's noise, and
the importer of the ASU granite shake-table tests; the method that compares a model with them is
:mod:`housner.scenarios.diagnosis`."""

from housner.scenarios.campaigns.asu import import_asu
from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.campaigns.campaign_records import MeasuredRecord, OutcomeRecord

__all__ = ["Campaign", "MeasuredRecord", "OutcomeRecord", "import_asu", "load_campaign"]
