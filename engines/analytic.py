"""The analytic Housner model as an engine (the reference), with every physical effect."""

from __future__ import annotations

from collections.abc import Sequence

from engines.base import Engine, check_response
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

    def simulate_many(self, specimen: Specimen, motions: list[GroundMotion], effects: Sequence = ()) -> list[Response]:
        """Simulate several records; the same results as calling ``simulate`` on each.

        Without effects the records go to the compiled batch solver
        (:func:`housner.model.simulate_many`, parallel over records).
        """
        if effects:
            return [self.simulate(specimen, m, effects) for m in motions]
        from housner.model import simulate_many

        kwargs = {"r": self.r}
        if self.substeps is not None:
            kwargs["substeps"] = self.substeps
        motions = list(motions)
        out = simulate_many(specimen, motions, **kwargs)
        return [check_response(r, self.name, m) for r, m in zip(out, motions, strict=True)]
