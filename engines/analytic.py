"""The analytic Housner model as an engine (the reference), with every physical effect."""

from __future__ import annotations

import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

from engines.base import RECORD_ERRORS, Engine, _check_errors, check_response
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = ["HousnerEngine"]


class _RegisteredEffects:
    """``effects_supported`` read live from the effect registry, on the class and on instances."""

    def __get__(self, obj, objtype=None) -> frozenset[str]:
        from housner.effects import available_effects

        return frozenset(available_effects())


class HousnerEngine(Engine):
    """Housner's rigid block on rigid ground, solved event-accurately (``housner.model``).

    It realises every effect of :data:`housner.effects.EFFECTS`, including
    those registered later by users (``@register_effect``) or by installed
    packages (entry-point group ``housner.effects``): parameter effects
    through :class:`housner.model.RockingParams`, mechanics effects through
    their own kernels, sensor effects on the response
    (:func:`housner.effects.apply_effects`).

    Parameters
    ----------
    r : float, optional
        Kinetic-energy ratio at impact [-]; default: the specimen's ``r_housner``.
        A ``restitution`` effect replaces it.
    substeps : int, optional
        Integrator substeps per motion sample; default: the solver's.
    """

    name = "housner"

    def __init__(self, r: float | None = None, substeps: int | None = None):
        self.r = r
        self.substeps = substeps

    effects_supported = _RegisteredEffects()  # the registry may grow after import

    def settings(self) -> dict:
        return {"r": self.r, "substeps": self.substeps}

    def version(self) -> str:
        import housner

        return housner.__version__

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        if not effects:
            from housner.model import simulate

            kwargs = {"r": self.r}
            if self.substeps is not None:
                kwargs["substeps"] = self.substeps
            return simulate(specimen, motion, **kwargs)
        from housner.effects import apply_effects
        from housner.model import RockingParams

        plan = apply_effects(specimen, motion, effects, params=RockingParams.from_specimen(specimen, r=self.r))
        return plan.run(substeps=self.substeps)

    def simulate_many(
        self, specimen: Specimen, motions: Sequence[GroundMotion], effects: Sequence = (), *, errors: str = "raise"
    ) -> list:
        """Simulate several records; the same results as calling ``simulate`` on each.

        Records whose effects keep Housner's equation of motion (parameter and
        sensor effects, or none) are solved together in one compiled call per
        parameter set (:func:`housner.model.simulate_many`, parallel over
        records); a batch that fails is redone record by record so that the
        failing one is named. Effects that replace the equation of motion
        (flexible foundation, sliding) run one record at a time in kernels
        that release the GIL, on threads.

        Parameters
        ----------
        specimen, motions, effects, errors
            As for :meth:`engines.base.Engine.simulate_many`.
        """
        from housner.effects import apply_effects
        from housner.model import RockingParams, simulate_many

        _check_errors(errors)
        motions = list(motions)
        effects = tuple(effects)
        self._refuse_unrealised(effects)
        base = RockingParams.from_specimen(specimen, r=self.r)
        plans = [apply_effects(specimen, m, effects, params=base) for m in motions]
        out: list = [None] * len(motions)
        groups: dict = {}
        for i, pl in enumerate(plans):
            if pl.solver is None:
                groups.setdefault(pl.params, []).append(i)
        for prm, idx in groups.items():
            try:
                res = simulate_many(specimen, [plans[i].motion for i in idx], params=prm, substeps=self.substeps)
            except RECORD_ERRORS:
                continue  # one record at a time below, so that the failing one is named
            for i, r in zip(idx, res, strict=True):
                out[i] = plans[i].observe(r)

        def run_one(i: int):
            try:
                return check_response(plans[i].run(substeps=self.substeps), self.name, motions[i])
            except RECORD_ERRORS as e:
                return e

        todo = [i for i in range(len(motions)) if out[i] is None]
        workers = min(len(todo), os.cpu_count() or 1)
        if workers > 1:
            with ThreadPoolExecutor(workers) as pool:
                for i, r in zip(todo, pool.map(run_one, todo), strict=True):
                    out[i] = r
        else:
            for i in todo:
                out[i] = run_one(i)
        for i, r in enumerate(out):
            if isinstance(r, Response):
                try:
                    out[i] = check_response(r, self.name, motions[i])
                except RECORD_ERRORS as e:
                    out[i] = e
            if errors == "raise" and isinstance(out[i], BaseException):
                raise out[i]
        return out
