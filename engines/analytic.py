"""The analytic Housner model as an engine (the reference), with every physical effect."""

from __future__ import annotations

import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

import housner
from housner.effects import EFFECTS, apply_effects, discover_effects
from housner.engines.base import RECORD_ERRORS, Engine, check_errors, check_response
from housner.model import REST_TOL, simulate
from housner.model import simulate_many as simulate_batch
from housner.motion import GroundMotion
from housner.response import Response
from housner.rocking_params import RockingParams
from housner.specimen import Specimen

__all__ = ["HousnerEngine"]


class _RegisteredEffects:
    """``effects_supported`` read live from the effect registry, on the class and on instances."""

    def __get__(self, obj, objtype=None) -> frozenset[str]:
        discover_effects()
        return frozenset(EFFECTS)  # probes included: the diagnosis runs them here


class HousnerEngine(Engine):
    """Housner's rigid block on rigid ground, solved event-accurately (``housner.model``).

    It realises every effect of :data:`housner.effects.EFFECTS`, including
    those registered later by users (``@register_effect``, plugin files,
    installed packages in the entry-point group ``housner.effects``):
    parameter effects through :class:`housner.rocking_params.RockingParams`, term
    effects through a kernel generated with their terms
    (:mod:`housner.effects.terms`), mechanics effects through their own
    kernels, sensor effects on the response (:func:`housner.effects.apply_effects`).

    Parameters
    ----------
    r : float, optional
        Kinetic-energy ratio at impact [-]; default: the specimen's ``r_housner``.
        A ``restitution`` effect replaces it.
    substeps : int, optional
        Integrator substeps per motion sample; default: the solver's.
    rest_tol : float
        Rest rule of the solver [-]: after an impact, a block whose next peak would stay below
        ``rest_tol * alpha`` is put at rest (:func:`housner.model.simulate`). The diagnosis' floor
        varies it, as two correct integrators differ in it.
    """

    name = "housner"

    def __init__(self, r: float | None = None, substeps: int | None = None, rest_tol: float = REST_TOL):
        self.r = r
        self.substeps = substeps
        self.rest_tol = float(rest_tol)

    effects_supported = _RegisteredEffects()  # the registry may grow after import

    def settings(self) -> dict:
        out = {"r": self.r, "substeps": self.substeps}
        if self.rest_tol != REST_TOL:  # only when changed: the default keeps the cache keys of earlier runs
            out["rest_tol"] = self.rest_tol
        return out

    def version(self) -> str:
        return housner.__version__

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        if not effects:
            kwargs = {"r": self.r}
            if self.substeps is not None:
                kwargs["substeps"] = self.substeps
            return simulate(specimen, motion, rest_tol=self.rest_tol, **kwargs)
        plan = apply_effects(specimen, motion, effects, params=RockingParams.from_specimen(specimen, r=self.r))
        return plan.run(substeps=self.substeps, rest_tol=self.rest_tol)

    def simulate_many(
        self, specimen: Specimen, motions: Sequence[GroundMotion], effects: Sequence = (), *, errors: str = "raise"
    ) -> list:
        """Simulate several records; the same results as calling ``simulate`` on each.

        Records whose effects keep Housner's equation of motion (parameter,
        term and sensor effects, or none) are solved together in one compiled
        call per parameter set and term set (:func:`housner.model.simulate_many`,
        parallel over records); a batch that fails is redone record by record so that the
        failing one is named. Effects that replace the equation of motion
        (flexible foundation, sliding) run one record at a time in kernels
        that release the GIL, on threads. Every response passes
        :func:`housner.engines.base.check_response`.

        Parameters
        ----------
        specimen, motions, effects, errors
            As for :meth:`housner.engines.base.Engine.simulate_many`.
        """
        check_errors(errors)
        motions = list(motions)
        effects = tuple(effects)
        self._refuse_unrealised(effects)
        base = RockingParams.from_specimen(specimen, r=self.r)
        plans = [apply_effects(specimen, m, effects, params=base) for m in motions]
        out = self._batched(specimen, plans)
        todo = [i for i, r in enumerate(out) if r is None]
        for i, r in zip(todo, self._one_by_one([plans[i] for i in todo]), strict=True):
            out[i] = r
        for i, r in enumerate(out):
            if isinstance(r, Response):
                try:
                    out[i] = check_response(r, self.name, motions[i])
                except RECORD_ERRORS as e:
                    out[i] = e
            if errors == "raise" and isinstance(out[i], BaseException):
                raise out[i]
        return out

    def _batched(self, specimen: Specimen, plans: list) -> list:
        """Responses of the plans that keep Housner's equation of motion, one compiled call per parameter set.

        Returns one entry per plan: its response, or None where it is left to
        :meth:`_one_by_one` (a mechanics effect, or a batch that failed).
        """
        out: list = [None] * len(plans)
        groups: dict = {}
        for i, pl in enumerate(plans):
            if pl.solver is None:  # Housner's kernel, with the effects' terms if any
                groups.setdefault((pl.params, pl.terms), []).append(i)
        for (prm, terms), idx in groups.items():
            try:
                res = simulate_batch(
                    specimen,
                    [plans[i].motion for i in idx],
                    params=prm,
                    substeps=self.substeps,
                    rest_tol=self.rest_tol,
                    terms=terms,
                )
            except RECORD_ERRORS:
                continue  # one record at a time, so that the failing one is named
            for i, r in zip(idx, res, strict=True):
                out[i] = plans[i].observe(r)
        return out

    def _one_by_one(self, plans: list) -> list:
        """Each plan run on its own (on threads when several): its response, or the exception it raised."""

        def run_one(plan):
            try:
                return plan.run(substeps=self.substeps, rest_tol=self.rest_tol)
            except RECORD_ERRORS as e:
                return e

        workers = min(len(plans), os.cpu_count() or 1)
        if workers > 1:
            with ThreadPoolExecutor(workers) as pool:
                return list(pool.map(run_one, plans))
        return [run_one(pl) for pl in plans]
