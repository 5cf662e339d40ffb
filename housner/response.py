"""The response of a rocking block to one record, the same for every engine."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Response"]


@dataclass(frozen=True, eq=False)
class Response:
    """Time history and summary of one simulation.

    Attributes
    ----------
    t : ndarray
        Sample times [s] (the motion's grid).
    theta : ndarray
        Rotation [rad]; theta > 0 leans toward +x on the +x pivot. After an
        overturn it is held at +-pi/2.
    theta_dot : ndarray
        Angular velocity [rad/s]; zero after an overturn.
    impact_times : ndarray
        Times at which theta crossed zero with an impact [s].
    theta_max : float
        Largest |theta| reached [rad] (between samples too); pi/2 when overturned.
    alpha : float
        The specimen's slenderness [rad], for normalising.
    overturned : bool
        True once |theta| reached pi/2.
    overturn_time : float
        Time of the overturn [s], NaN when the block did not fall.
    uplift_time : float
        First time the block left the rest position [s], NaN if it never rocked.
    engine : str
        Name of the engine that produced it.
    info : dict
        Engine-specific extras (settings, step counts, warnings).
    """

    t: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    impact_times: np.ndarray
    theta_max: float
    alpha: float
    overturned: bool
    overturn_time: float = math.nan
    uplift_time: float = math.nan
    engine: str = "housner"
    info: dict = field(default_factory=dict)

    @classmethod
    def from_kernel(cls, t, theta, theta_dot, impact_times, summary, alpha: float, info: dict) -> Response:
        """The analytic engine's Response from the summary a compiled kernel returns.

        ``summary`` starts with (theta_max [rad], overturned, overturn time [s],
        uplift time [s]), as every kernel of :mod:`housner._kernel` and of the
        mechanics effects returns it; theta_max is set to pi/2 when overturned.
        """
        theta_max, overturned, t_over, t_uplift = summary[:4]
        return cls(
            t=t,
            theta=theta,
            theta_dot=theta_dot,
            impact_times=impact_times,
            theta_max=math.pi / 2 if overturned else float(theta_max),
            alpha=alpha,
            overturned=bool(overturned),
            overturn_time=float(t_over),
            uplift_time=float(t_uplift),
            engine="housner",
            info=info,
        )

    @property
    def theta_max_over_alpha(self) -> float:
        """theta_max / alpha [-]; +inf when the block overturned."""
        return math.inf if self.overturned else self.theta_max / self.alpha

    @property
    def n_impacts(self) -> int:
        """Number of impacts."""
        return int(len(self.impact_times))

    @property
    def rocked(self) -> bool:
        """True if the block ever left its rest position."""
        return not math.isnan(self.uplift_time) or self.theta_max > 0.0

    def summary(self) -> dict:
        """One results-table row: theta_max_over_alpha, overturned, n_impacts, ..."""
        return {
            "theta_max_over_alpha": self.theta_max_over_alpha,
            "theta_max": self.theta_max,
            "overturned": bool(self.overturned),
            "n_impacts": self.n_impacts,
            "overturn_time": self.overturn_time,
            "uplift_time": self.uplift_time,
        }
