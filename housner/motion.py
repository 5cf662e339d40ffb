"""Ground motions: uniformly sampled horizontal ground acceleration [m/s^2], and optional extra channels.

Accelerations are stored in m/s^2 (SI inside); the readers (:mod:`housner.readers.measured_data`) convert
once, from the units a file's header names. Between samples the acceleration is taken as
linear in time.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from housner.readers.measured_data import CHANNEL_PREFIX
from housner.readers.motion_files import read_at2, read_csv_motion

__all__ = ["VERTICAL", "GroundMotion"]

#: The vertical table acceleration [m/s^2], positive upward (g -> g + a_v).
VERTICAL = "ground_acc_vertical"


class _Channels(dict):
    """A motion's channels: a dict that cannot be changed once built (and pickles as one)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("a GroundMotion's channels cannot be changed; build a new motion (dataclasses.replace)")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = __ior__ = _refuse

    def __reduce__(self):
        return (_Channels, (dict(self),))


#: Corner frequency of the high-pass before a record's acceleration is integrated into a PGV [Hz].
PGV_HIGHPASS = 0.1


@dataclass(frozen=True, eq=False)
class GroundMotion:
    """Horizontal ground acceleration sampled at a uniform step.

    Parameters
    ----------
    acc : array_like
        Ground acceleration ug''(t_k) [m/s^2], positive along +x, t_k = k dt.
    dt : float
        Sample step [s].
    name : str
        Identifier used in results tables and messages.
    provenance : str
        Where the samples came from (file, generator and seed, scaling).
    theta0, theta_dot0 : float
        Initial state of the block at t = 0 [rad, rad/s]; non-zero for a
        free-vibration release. Engines start from it.
    channels : mapping of str to array_like, optional
        Extra measured accelerations [m/s^2] on the same sample grid, each as
        long as ``acc``, named ``ground_acc_<what>``: :data:`VERTICAL`
        (``"ground_acc_vertical"``, the vertical table acceleration, positive
        up) is the one the library's kernel reads. Effects declare the channels
        they read (``Effect.channels``). Carried through :meth:`scaled` (scaled
        with the amplitude, like ``acc``), :meth:`with_duration`,
        :meth:`sliced`, ``dataclasses.replace`` and :meth:`content_hash`.

    Notes
    -----
    Samples are linear between grid points; ``t`` = k dt, k = 0 .. n-1.
    """

    acc: np.ndarray
    dt: float
    name: str = "motion"
    provenance: str = ""
    theta0: float = 0.0
    theta_dot0: float = 0.0
    channels: Mapping[str, np.ndarray] = field(default_factory=dict)
    _hash: str | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        try:
            acc = np.array(self.acc, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"`acc` of motion {self.name!r} must be numeric") from None
        if acc.ndim != 1:
            raise ValueError(f"`acc` of motion {self.name!r} must be one-dimensional, got shape {acc.shape}")
        if acc.size == 0:
            raise ValueError(f"`acc` of motion {self.name!r} is empty")
        bad = np.flatnonzero(~np.isfinite(acc))
        if bad.size:
            raise ValueError(f"`acc` of motion {self.name!r} is not finite at sample {bad[0]} (value {acc[bad[0]]})")
        dt = float(self.dt)
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"`dt` of motion {self.name!r} must be positive and finite, got {self.dt!r}")
        for key in ("theta0", "theta_dot0"):
            v = float(getattr(self, key))
            if not math.isfinite(v):
                raise ValueError(f"`{key}` of motion {self.name!r} must be finite, got {v!r}")
            object.__setattr__(self, key, v)
        if abs(self.theta0) >= math.pi / 2:
            raise ValueError(f"`theta0` of motion {self.name!r} must lie within (-pi/2, pi/2), got {self.theta0}")
        acc.setflags(write=False)
        object.__setattr__(self, "acc", acc)
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "channels", self._checked_channels(self.channels, acc.size))

    def _checked_channels(self, channels, n: int) -> Mapping[str, np.ndarray]:
        if not isinstance(channels, Mapping):
            raise ValueError(f"`channels` of motion {self.name!r} must be a mapping of name -> samples")
        out = {}
        for key in sorted(channels):
            if not (
                isinstance(key, str)
                and key.startswith(CHANNEL_PREFIX)
                and key.isidentifier()
                and len(key) > len(CHANNEL_PREFIX)
            ):
                raise ValueError(
                    f"channel {key!r} of motion {self.name!r}: a channel is an acceleration named "
                    f"'{CHANNEL_PREFIX}<what>' (e.g. {VERTICAL!r})"
                )
            try:
                a = np.array(channels[key], dtype=np.float64)
            except (TypeError, ValueError):
                raise ValueError(f"channel {key!r} of motion {self.name!r} must be numeric") from None
            if a.shape != (n,):
                raise ValueError(
                    f"channel {key!r} of motion {self.name!r} must have one sample per sample of `acc` ({n}), "
                    f"got shape {a.shape}"
                )
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                raise ValueError(f"channel {key!r} of motion {self.name!r} is not finite at sample {bad[0]}")
            a.setflags(write=False)
            out[key] = a
        return _Channels(out)

    # ------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.acc.size)

    def __len__(self) -> int:
        return self.n

    @property
    def duration(self) -> float:
        """Time of the last sample, (n - 1) dt [s]."""
        return (self.n - 1) * self.dt

    @property
    def t(self) -> np.ndarray:
        """Sample times [s]."""
        return np.arange(self.n) * self.dt

    @property
    def pga(self) -> float:
        """Peak ground acceleration max |ug''| [m/s^2]."""
        return float(np.max(np.abs(self.acc)))

    def pgv(self, highpass: float = PGV_HIGHPASS) -> float:
        """Peak ground velocity [m/s]: the acceleration integrated (trapezoids) after a zero-phase 4th-order
        Butterworth high-pass at ``highpass`` [Hz], which removes the drift that a sensor's offset integrates
        into (prefer a measured displacement channel where there is one)."""
        from scipy import signal

        a = np.asarray(self.acc, dtype=float)
        if highpass > 0 and a.size > 27:
            sos = signal.butter(4, highpass, btype="highpass", fs=1.0 / self.dt, output="sos")
            a = signal.sosfiltfilt(sos, a)
        v = np.concatenate(([0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * self.dt)))
        return float(np.max(np.abs(v - v.mean())))

    def content_hash(self) -> str:
        """SHA-256 of samples, step, initial state and channels (for result caching).

        A motion without channels hashes as it did before channels existed.
        """
        if self._hash is None:
            h = hashlib.sha256()
            h.update(np.ascontiguousarray(self.acc).tobytes())
            h.update(np.array([self.dt, self.theta0, self.theta_dot0]).tobytes())
            for key, a in self.channels.items():  # sorted by name
                h.update(b"\0channel\0" + key.encode() + b"\0")
                h.update(np.ascontiguousarray(a).tobytes())
            object.__setattr__(self, "_hash", h.hexdigest())
        return self._hash

    # ------------------------------------------------------------------
    def scaled(self, amplitude: float = 1.0, time: float = 1.0, name: str | None = None) -> GroundMotion:
        """Scale amplitude and time.

        Parameters
        ----------
        amplitude : float
            Factor on the accelerations [-].
        time : float
            Factor on the time axis [-]: the new step is ``time * dt``. The
            sqrt(S) compression from a prototype S times larger to the model
            (seed eq. 9, omega_model = omega_prototype sqrt(S)) is
            ``time = 1 / sqrt(S)``; see :meth:`to_model_scale`.
        """
        for key, v in (("amplitude", amplitude), ("time", time)):
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise ValueError(f"`{key}` must be a finite number, got {v!r}")
        if time <= 0:
            raise ValueError(f"`time` must be positive, got {time!r}")
        prov = self.provenance
        if amplitude != 1.0 or time != 1.0:
            prov = f"{prov}; scaled amplitude x{amplitude:g}, time x{time:g}".lstrip("; ")
        return GroundMotion(
            acc=self.acc * amplitude,
            dt=self.dt * time,
            name=name or self.name,
            provenance=prov,
            theta0=self.theta0,
            theta_dot0=self.theta_dot0 / time,
            channels={k: a * amplitude for k, a in self.channels.items()},
        )

    def to_model_scale(self, S: float) -> GroundMotion:
        """Compress time by sqrt(S) for a model S times smaller than the prototype (seed eq. 9)."""
        if not (math.isfinite(S) and S > 0):
            raise ValueError(f"`S` must be positive and finite, got {S!r}")
        return self.scaled(time=1.0 / math.sqrt(S))

    def with_duration(self, duration: float) -> GroundMotion:
        """Cut or pad with zeros to ``duration`` [s] (free rocking after the shaking)."""
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(f"`duration` must be positive and finite, got {duration!r}")
        n = int(round(duration / self.dt)) + 1
        k = min(n, self.n)

        def fit(a):
            out = np.zeros(n)
            out[:k] = a[:k]
            return out

        channels = {key: fit(a) for key, a in self.channels.items()}
        return GroundMotion(fit(self.acc), self.dt, self.name, self.provenance, self.theta0, self.theta_dot0, channels)

    def sliced(self, start: int = 0, stop: int | None = None) -> GroundMotion:
        """Samples ``start:stop`` (Python slice rules, step 1) of the motion and of its channels.

        The new motion starts at t = 0 with this one's initial state (theta0, theta_dot0).
        """
        k = range(self.n)[slice(start, stop)]
        if len(k) == 0:
            raise ValueError(f"`sliced({start!r}, {stop!r})` of motion {self.name!r} ({self.n} samples) is empty")
        sl = slice(k.start, k.stop)
        return GroundMotion(
            self.acc[sl],
            self.dt,
            self.name,
            self.provenance,
            self.theta0,
            self.theta_dot0,
            {key: a[sl] for key, a in self.channels.items()},
        )

    @classmethod
    def free_vibration(cls, theta0: float, duration: float, dt: float = 0.002, name: str | None = None) -> GroundMotion:
        """No ground motion; the block is released at rest from ``theta0`` [rad]."""
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(f"`duration` must be positive and finite, got {duration!r}")
        n = int(round(duration / dt)) + 1
        return cls(np.zeros(n), dt, name or f"free vibration theta0={theta0:.4g}", "free-vibration release", theta0)

    # ------------------------------------------------------------------

    @classmethod
    def from_at2(cls, path: str | Path, name: str | None = None, *, units: str | None = None) -> GroundMotion:
        """Read a PEER AT2 record in the units its header names (:func:`housner.readers.motion_files.read_at2`).

        ``units``: the acceleration unit when the header names none (e.g. ``"g"``); if the header
        names one, it must agree. ``name`` defaults to the file's stem.
        """
        acc, dt, provenance = read_at2(path, units=units)
        return cls(acc=acc, dt=dt, name=name or Path(path).stem, provenance=provenance)

    @classmethod
    def from_csv(
        cls,
        path: str | Path,
        *,
        time_column: str = "time",
        acc_column: str = "ground_acc",
        units: str | None = None,
        name: str | None = None,
    ) -> GroundMotion:
        """Read a CSV record: time and acceleration columns, units in the header, extra ``ground_acc_<what>``
        columns as channels (:func:`housner.readers.motion_files.read_csv_motion`). ``name`` defaults to the file's
        stem."""
        acc, dt, provenance, channels = read_csv_motion(
            path, time_column=time_column, acc_column=acc_column, units=units
        )
        return cls(acc=acc, dt=dt, name=name or Path(path).stem, provenance=provenance, channels=channels)
