"""The analytic Housner model as an engine (the reference)."""

from __future__ import annotations

from engines.base import Engine
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = ["HousnerEngine"]


class HousnerEngine(Engine):
    """Housner's rigid block on rigid ground, solved event-accurately (``housner.model``).

    Parameters
    ----------
    r : float, optional
        Kinetic-energy ratio at impact [-]; default: the specimen's ``r_housner``.
    substeps : int, optional
        Integrator substeps per motion sample; default: the solver's.
    """

    name = "housner"

    def __init__(self, r: float | None = None, substeps: int | None = None):
        self.r = r
        self.substeps = substeps

    def settings(self) -> dict:
        return {"r": self.r, "substeps": self.substeps}

    def version(self) -> str:
        import housner

        return housner.__version__

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        from housner.model import simulate

        kwargs = {"r": self.r}
        if self.substeps is not None:
            kwargs["substeps"] = self.substeps
        return simulate(specimen, motion, **kwargs)

    def simulate_many(self, specimen: Specimen, motions: list[GroundMotion]) -> list[Response]:
        """Simulate several records (same as calling ``simulate`` on each)."""
        return [self.simulate(specimen, m) for m in motions]
