"""Sensor effects: what an instrument records instead of the rotation (angle offset, channel time lag)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from housner.effects.registry import STAGE_SENSOR, Effect, param, register_effect


# ----------------------------------------------------------------------
# sensor effects
@register_effect
@dataclass(frozen=True)
class SensorOffset(Effect):
    """A constant offset added to the measured rotation.

    The observed theta is theta + offset [rad] at every sample (the seed's
    optical system had an offset between its marker lines that was measured
    at rest and subtracted; a residual remains). ``theta_max`` becomes the
    largest |theta + offset|: exact at the response's own (between-sample)
    peak on its side, sampled on the other side. Impact, uplift and overturn
    times are those of the block. A record released from a measured tilt
    (free vibration) starts from the measured angle less the offset.

    Parameters
    ----------
    offset : float
        Offset [rad], in [-0.05, 0.05]; neutral 0.

    References
    ----------
    Bachmann et al. (2017), section 3.4 (angle accuracy 0.8 mrad; the initial
    offset is subtracted in post-processing).
    """

    name = "sensor_offset"
    stage = STAGE_SENSOR
    offset: float = param("rad", (-0.05, 0.05), neutral=0.0, default=0.0, doc="constant offset of the measured angle")

    @classmethod
    def measured_params(cls, metrics, specimen):
        """The rotation read at rest (``tilt_offset`` [alpha]) when it is measured beyond 3 standard errors."""
        m = metrics.get("tilt_offset")
        if m is None or not (math.isfinite(m.value) and math.isfinite(m.se)) or abs(m.value) <= 3.0 * m.se:
            return None
        return {"offset": float(m.value) * specimen.alpha}

    def transform_input(self, motion):
        # a block released from a measured tilt was released from the measured angle less the offset
        if self.offset == 0.0 or motion.theta0 == 0.0:
            return motion
        return replace(motion, theta0=motion.theta0 - self.offset)

    def observe(self, response):
        if self.offset == 0.0:
            return response
        th = response.theta
        hi, lo = float(np.max(th)), float(-np.min(th))
        if hi >= lo:
            hi = max(hi, response.theta_max)
        else:
            lo = max(lo, response.theta_max)
        theta_max = max(hi + self.offset, lo - self.offset, 0.0)
        if response.overturned:
            theta_max = math.pi / 2
        return replace(
            response,
            theta=th + self.offset,
            theta_max=theta_max,
            info={**response.info, "sensor_offset": self.offset},
        )


@register_effect
@dataclass(frozen=True)
class TimeLag(Effect):
    """The rotation channel lags the ground-acceleration channel by tau.

    The observed theta(t) is the block's theta(t - tau), linearly interpolated
    between samples (exact sample values when tau is a multiple of dt); before
    the record starts (t < tau) the initial state is held, beyond its end the
    last value. theta' is shifted the same way; impact, uplift and overturn
    times are moved by +tau. ``theta_max`` stays the block's own (between
    samples) if its sampled peak is inside the observed window, else it is the
    largest observed |theta|. Positive tau delays theta.

    Parameters
    ----------
    tau : float
        Lag of theta behind ground_acc [s], in [-0.1, 0.1]; neutral 0.

    References
    ----------
    Bachmann et al. (2017), section 3.4 (table and block measured by separate
    channels at 500 Hz).
    """

    name = "time_lag"
    stage = STAGE_SENSOR
    # a free vibration has no ground channel to lag behind, and a measured one starts at the release
    # its theta channel shows (housner.scenarios.campaigns.campaign_records.estimate_release), which already carries
    # the lag
    seen_in_free_vibration = False
    tau: float = param("s", (-0.1, 0.1), neutral=0.0, default=0.0, doc="lag of the theta channel behind ground_acc")

    def observe(self, response):
        if self.tau == 0.0:
            return response
        t = response.t
        n = t.size
        dt = float(t[1] - t[0]) if n > 1 else 1.0
        idx = np.arange(n, dtype=np.float64)
        src = idx - self.tau / dt
        theta = np.interp(src, idx, response.theta)
        theta_dot = np.interp(src, idx, response.theta_dot)
        k = int(np.argmax(np.abs(response.theta)))  # sample k is observed at index k + tau/dt
        if response.overturned or 0.0 <= k + self.tau / dt <= n - 1:
            theta_max = response.theta_max
        else:
            theta_max = float(np.max(np.abs(theta)))
        return replace(
            response,
            theta=theta,
            theta_dot=theta_dot,
            theta_max=theta_max,
            impact_times=response.impact_times + self.tau,
            uplift_time=response.uplift_time + self.tau,
            overturn_time=response.overturn_time + self.tau,
            info={**response.info, "time_lag": self.tau},
        )
