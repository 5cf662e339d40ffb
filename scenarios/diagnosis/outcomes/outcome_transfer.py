"""Transfer: an outcome model fitted on one campaign, frozen, scored on another beside the baselines fitted on the
first campaign, frozen too (``housner diagnose CAMPAIGN --model FITTED.json``). Whether a model fitted on one rock
predicts another is the test a fitted parameter must pass before anyone trusts it on a rock nobody shook."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from housner._values import read_as
from housner.scenarios.diagnosis.outcomes.outcome_effects import OutcomeEffect, outcome_effects
from housner.scenarios.diagnosis.outcomes.outcome_models import (
    ALPHA_GRID,
    OUTCOME_MODELS,
    Geometry,
    known_model,
    outcome_model,
    overturn_tables,
)
from housner.scenarios.diagnosis.outcomes.outcome_scores import OutcomeScores, outcome_scores
from housner.scenarios.diagnosis.outcomes.outcome_validation import (
    BASELINES,
    BaselineFit,
    PairedComparison,
    compare_log_loss,
)

__all__ = ["FrozenOutcomeModel", "OutcomeTransfer", "read_frozen_model", "transfer_outcomes"]

#: The frozen contact's grid of alpha spans its fitted alpha_eff times exp(+-this many spreads) [-].
SPREADS_COVERED = 3.0


@dataclass(frozen=True)
class FrozenOutcomeModel:
    """An outcome model as another campaign's diagnosis fitted it, on all of that campaign's records.

    Attributes
    ----------
    source : str
        The campaign it was fitted on.
    name : str
        ``"plain"`` or its effects joined by "+".
    params : dict
        Its parameters (alpha_eff [rad], spread [-], r [-], lapse [-], as the model holds them).
    baselines : dict of str to BaselineFit
        The baselines fitted on the same campaign.
    """

    source: str
    name: str
    params: dict
    baselines: dict[str, BaselineFit]


def read_frozen_model(path: str | Path) -> FrozenOutcomeModel:
    """The final model and the baselines of an outcome diagnosis JSON (``housner diagnose --json``; a campaign of
    both kinds holds it under ``outcomes_diagnosis``).

    Raises
    ------
    ValueError
        One line naming the file: not JSON, not an outcome diagnosis, or one written before its baselines' fits
        were kept.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: cannot read it as a diagnosis JSON ({type(e).__name__}: {e})") from None
    if isinstance(data, dict) and "outcomes_diagnosis" in data:
        data = data["outcomes_diagnosis"]
    if not isinstance(data, dict) or data.get("kind") != "outcomes" or not data.get("ladder"):
        raise ValueError(f"{path}: not the JSON of an outcome diagnosis (housner diagnose --json on outcome records)")
    fits = data.get("baseline_fits")
    if not isinstance(fits, dict) or set(fits) != set(BASELINES):
        raise ValueError(f"{path}: holds no fitted baselines; diagnose its campaign again with this version")
    final = data["ladder"][-1]
    if not known_model(final["name"]):
        raise ValueError(f"{path}: its model {final['name']!r} is no outcome model of this version's effects")
    baselines = {n: read_as(BaselineFit, v) for n, v in fits.items()}
    return FrozenOutcomeModel(str(data.get("campaign", path.stem)), final["name"], dict(final["params"]), baselines)


def _frozen_effect(frozen: FrozenOutcomeModel, specimen) -> list[OutcomeEffect]:
    """The frozen model's library effect, tabulated at its fitted value only (none for the models with tables of
    their own)."""
    if frozen.name in OUTCOME_MODELS:
        return []
    found, _left = outcome_effects(specimen, [frozen.name])
    return [e.at(float(frozen.params[e.param])) for e in found if e.param in frozen.params]


@dataclass(frozen=True)
class OutcomeTransfer:
    """A frozen model's predictions of another campaign's outcomes, beside the frozen baselines'.

    Attributes
    ----------
    source : str
        The campaign the model and the baselines were fitted on.
    model : str
    params : dict
    scores : OutcomeScores
        The frozen model's scores on this campaign (intervals resampling whole ground motions).
    baselines : dict of str to OutcomeScores
        The frozen baselines' scores.
    against : dict of str to PairedComparison
        The frozen model against each frozen baseline, record by record, clustered by ground motion.
    p : ndarray
        The frozen model's P(overturn) per record [-].
    """

    source: str
    model: str
    params: dict
    scores: OutcomeScores
    baselines: dict[str, OutcomeScores]
    against: dict[str, PairedComparison]
    p: np.ndarray = field(compare=False, default=None, repr=False)


def transfer_outcomes(
    frozen: FrozenOutcomeModel, motions, geo: Geometry, specimen, y, pga, pgv, groups, *, seed: int, say
) -> OutcomeTransfer:
    """Score ``frozen`` on the records (table motions ``motions``, outcomes ``y``, peaks ``pga`` [m/s^2] and ``pgv``
    [m/s], ``groups``) of the block ``geo``: nothing is fitted on them.

    The model keeps its parameters: an effective contact keeps its alpha_eff [rad] and spread, run on this
    block's mass, height and inertia over a grid of alpha around them; a library effect keeps its value, the
    lapse and r stay as fitted. Only the frozen model's own tables are run (the plain ensemble, and the contact's
    or the effect's).
    """
    params = frozen.params
    alphas = np.empty(0)  # no contact table, unless the model has a contact
    if "alpha_eff" in params:
        half = SPREADS_COVERED * max(float(params["spread"]), 0.02)
        alphas = float(params["alpha_eff"]) * np.exp(np.linspace(-half, half, ALPHA_GRID))
        alphas = alphas[alphas < math.pi / 2 - 1e-3]
    tables = overturn_tables(motions, geo, specimen, say, alphas=alphas, effects=_frozen_effect(frozen, specimen))
    predict, _fit = outcome_model(frozen.name)
    p = predict(tables, np.arange(len(motions)), params)
    base_p = {n: fit.predict(pga, pgv) for n, fit in frozen.baselines.items()}
    say(f"transfer from {frozen.source}: {frozen.name} frozen")
    return OutcomeTransfer(
        source=frozen.source,
        model=frozen.name,
        params=dict(params),
        scores=outcome_scores(p, y, groups=groups, seed=seed),
        baselines={n: outcome_scores(q, y, groups=groups, seed=seed) for n, q in base_p.items()},
        against={n: compare_log_loss(p, q, y, groups) for n, q in base_p.items()},
        p=p,
    )
