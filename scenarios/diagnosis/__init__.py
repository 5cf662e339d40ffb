"""The diagnosis of a measured campaign: the model against the measurements, where it fails, which effect is
missing (a cross-validated forward selection over the effect library) and the verdict against what a correct
model would leave. The story is in ``docs/explanation/diagnosis.md``."""

from housner.scenarios.diagnosis.comparison import compare
from housner.scenarios.diagnosis.diagnose import diagnose
from housner.scenarios.diagnosis.outcomes import OutcomeDiagnosis, diagnose_outcomes
from housner.scenarios.diagnosis.results import Diagnosis

__all__ = ["Diagnosis", "OutcomeDiagnosis", "compare", "diagnose", "diagnose_outcomes"]
