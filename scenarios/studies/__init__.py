"""Studies: stripes of intensity x specimen sizes x engines -> fragility curves with intervals."""

from housner.scenarios.catalogue.study_table import Study
from housner.scenarios.studies.fragility import fit_lognormal, fragility_curve
from housner.scenarios.studies.study import StudyResult, load_study, run_study

__all__ = ["Study", "StudyResult", "fit_lognormal", "fragility_curve", "load_study", "run_study"]
