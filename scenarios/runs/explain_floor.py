"""The floor of ``housner explain``: the record-by-record agreement a correct model could still miss.

Two parts bound what a correct model could show: the chaos floor
(:func:`housner.scenarios.runs.chaos.chaos_floor`, the analytic model against itself with r and p perturbed
by the engine's measured free-rocking errors) and the model-form floor (:func:`model_form_floor`, the
analytic model against itself under the conventions two correct integrators differ in,
:data:`PERTURBATIONS`, each one
:class:`housner.scenarios.diagnosis.verdict.integrator_families.ModelForm` at the edge of the range the
diagnosis' floor draws from, the input's timing shifted by :data:`SHIFT` = 3/8 of a sample).
:func:`extended_floor` is the lower of the two. Why these conventions, and why 3/8 and not 1/2, are in
``docs/how-to/explain-engine.md`` (step 4).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from housner._values import JsonValue
from housner.engines.base import get_engine
from housner.model import default_substeps
from housner.motion import GroundMotion
from housner.scenarios.diagnosis.verdict.integrator_families import SCALE_SD, SHIFT_SAMPLES, UPSAMPLE, ModelForm
from housner.scenarios.runs.chaos import RECORD_RTOL, AgreementShares, ChaosFloor, chaos_floor, measure_engine_errors
from housner.specimen import Specimen
from housner.statistics.ensemble_stats import per_record_agreement

__all__ = [
    "PERTURBATIONS",
    "SHIFT",
    "FloorParts",
    "ModelFormFloor",
    "engine_chaos_floor",
    "extended_floor",
    "model_form_floor",
]


#: Sub-sample timing of the input [samples] (docs/how-to/explain-engine.md, step 4: 1/2 less half a step of the
#: finer grid).
SHIFT = SHIFT_SAMPLES - 0.5 / UPSAMPLE

#: The conventions two correct integrators of Housner's equation differ in, each at the edge of the
#: range the diagnosis' floor draws from (:mod:`housner.scenarios.diagnosis.verdict.integrator_families`): label ->
# form.
PERTURBATIONS: dict[str, ModelForm] = {
    "held": ModelForm(convention="held"),
    "shift+": ModelForm(shift=SHIFT),
    "shift-": ModelForm(shift=-SHIFT),
    "scale+": ModelForm(scale=1.0 + SCALE_SD),
    "scale-": ModelForm(scale=1.0 - SCALE_SD),
    "substeps x2": ModelForm(substep_factor=2),
}


@dataclass(frozen=True, eq=False)
class FloorParts(JsonValue):
    """The two parts of the extended floor, their mean shares [-]: the chaos floor of the engine's errors and the
    model-form floor of another correct integrator (:func:`extended_floor` is the lower)."""

    chaos: float = math.nan
    model_form: float = math.nan


@dataclass(frozen=True, eq=False)
class ModelFormFloor(AgreementShares):
    """:class:`housner.scenarios.runs.chaos.AgreementShares` under another correct integrator's conventions
    (one share per perturbation of :data:`PERTURBATIONS`)."""

    #: Integrator substeps per sample of the unperturbed run, on the grid :data:`UPSAMPLE` times finer than the
    #: records' [-].
    substeps: int = 0


def model_form_floor(
    specimen: Specimen,
    motions: Sequence[GroundMotion],
    settings: Mapping | None = None,
    *,
    rtol: float = RECORD_RTOL,
    atol: float = 0.0,
) -> ModelFormFloor:
    """The analytic model's record-by-record agreement with itself under :data:`PERTURBATIONS`.

    Every run, the unperturbed one included, feeds the block the input on a grid
    :data:`~housner.scenarios.diagnosis.verdict.integrator_families.UPSAMPLE` times finer than the record's
    (:meth:`ModelForm.felt`), so that each perturbation differs from the reference in itself alone.

    Parameters
    ----------
    specimen : Specimen
    motions : sequence of GroundMotion
        The ground motions (the ones the engine ran), each starting at rest.
    settings : mapping, optional
        Settings of the analytic engine (``r``; ``substeps`` per sample of the records).
    rtol, atol : float
        Tolerances of :func:`housner.statistics.ensemble_stats.per_record_agreement` [-].

    Returns
    -------
    ModelFormFloor
    """
    if not motions:
        raise ValueError("`motions` is empty: the model-form floor needs at least one ground motion")
    settings = dict(settings or {})
    sub = settings.pop("substeps", None)
    dt_fine = max(m.dt for m in motions) / UPSAMPLE
    # the records' substeps spread over the finer grid, or the solver's own rule (p h <= PH_MAX) on it
    base = max(1, math.ceil(int(sub) / UPSAMPLE)) if sub else default_substeps(specimen.frequency_parameter, dt_fine)

    def theta(form: ModelForm) -> np.ndarray:
        eng = get_engine("housner", **settings, substeps=form.substep_factor * base)
        out = eng.simulate_many(specimen, [form.felt(m) for m in motions])
        return np.array([r.theta_max_over_alpha for r in out], dtype=float)

    ref = theta(ModelForm())
    shares, verdicts = {}, {}
    for label, form in PERTURBATIONS.items():
        ag = per_record_agreement(theta(form), ref, rtol=rtol, atol=atol)
        shares[label], verdicts[label] = ag.share, ag.verdict_share
    return ModelFormFloor(substeps=int(base), **AgreementShares.summarised(shares, verdicts, ref.size))


def engine_chaos_floor(
    engine: str,
    engine_settings: Mapping | None,
    specimen: Specimen,
    motions: Sequence[GroundMotion],
    r: float | None = None,
    *,
    rtol: float = RECORD_RTOL,
    atol: float = 0.0,
) -> ChaosFloor:
    """The chaos floor of an engine: its free-rocking r and p errors measured, the analytic model perturbed by them.

    As ``housner run`` measures the errors (:func:`housner.scenarios.runs.chaos.run_engine_errors`:
    releases sampled at the ensemble's median step, r against the analytic model's r) and as its
    report computes the floor (``housner.scenarios.runs.view.Run.chaos_floors``).

    Parameters
    ----------
    engine : str
        Registry name of the engine.
    engine_settings : mapping, optional
        Its settings.
    specimen : Specimen
    motions : sequence of GroundMotion
        The ground motions the floor is measured on.
    r : float, optional
        The analytic model's r [-] (default: Housner's).
    rtol, atol : float
        Tolerances of :func:`housner.statistics.ensemble_stats.per_record_agreement` [-].

    Returns
    -------
    ChaosFloor
        A floor of 1 (no perturbation) for an engine without measurable errors (the analytic engine).
    """
    dt = float(np.median([m.dt for m in motions]))
    errors = measure_engine_errors(get_engine(engine, **dict(engine_settings or {})), specimen, r_reference=r, dt=dt)
    return chaos_floor(specimen, motions, errors, r=r, rtol=rtol, atol=atol)


def extended_floor(chaos: ChaosFloor, model_form: ModelFormFloor) -> float:
    """The lower of the chaos floor's and the model-form floor's mean shares [-]."""
    return float(min(chaos.share, model_form.share))
