"""What two correct integrators of the same model differ in: the model-form part of the diagnosis' floor.

A measurement is never produced by the model's own integrator. Two correct solvers of Housner's equation,
fed the same recorded table acceleration, differ in conventions that no campaign states and none can
recover: the table between samples (:data:`CONVENTIONS`), the samples' timing (:data:`SHIFT_SAMPLES`), the
amplitude (:data:`SCALE_SD`), the rest rule (:data:`REST_TOL_RANGE`), the step (:data:`SUBSTEP_FACTORS`) and
the acceleration channel's noise (:func:`acc_channel_noise`). The floor of
:func:`housner.scenarios.diagnosis.verdict.correct_model_floor.measure_floor` draws one :class:`ModelForm`
per replica, from nested families, and produces its "measurement" with it. Why these differences matter
(rocking is chaotic), and why each range is a convention and not a fit, are in
``docs/explanation/diagnosis.md`` ("The floor").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from housner.free_vibration.calibration import estimate_noise
from housner.model import REST_TOL, default_substeps
from housner.motion import GroundMotion
from housner.scenarios.diagnosis.comparison.record_comparison import simulate_records

__all__ = [
    "CONVENTIONS",
    "FAMILIES",
    "REST_TOL_RANGE",
    "SCALE_SD",
    "SHIFT_SAMPLES",
    "SUBSTEP_FACTORS",
    "UPSAMPLE",
    "ModelForm",
    "acc_channel_noise",
]

#: How the table acceleration runs between two samples.
CONVENTIONS = ("linear", "held")
#: Half-width of the uniform sub-sample timing of the input [samples].
SHIFT_SAMPLES = 0.5
#: Relative standard deviation of the input amplitude [-].
SCALE_SD = 1e-3
#: Range of the rest rule, drawn log-uniform [-] (next peak over alpha below which the block rests).
REST_TOL_RANGE = (1e-9, 1e-4)
#: Multiples of the library's integrator substeps.
SUBSTEP_FACTORS = (1, 2, 4)
#: Families of correct integrators, nested, closest to the library's first: name -> (share lambda of
#: the input's timing and amplitude ranges they span [-], whether their rest rule and step differ).
#: "exact": the library's own integrator (only the acceleration channel's noise); "solver": another
#: rest rule and step on the same input; "input-x": and the input's timing and amplitude within x of
#: their ranges, linear between samples; "any": the whole ranges, held or linear.
FAMILIES: dict[str, tuple[float, bool]] = {
    "exact": (0.0, False),
    "solver": (0.0, True),
    "input-0.03": (0.03, True),
    "input-0.1": (0.1, True),
    "input-0.3": (0.3, True),
    "any": (1.0, True),
}
#: Share of a ground motion's samples at each end where the table may be still [-].
QUIET_SHARE = 0.1
#: The truth runs on a grid this many times finer than the record's, so that "held" and a sub-sample
#: shift are inputs the (linear-in-sample) kernel realises [-].
UPSAMPLE = 4


def acc_channel_noise(campaign) -> float:
    """Noise of the ground-acceleration channel [m/s^2], read where the table is still.

    The root mean square about its mean of the free vibrations' ``ground_acc`` when it was recorded
    (not all zeros). Otherwise, per ground motion, the robust third-difference estimate
    (:func:`housner.free_vibration.calibration.estimate_noise`) on its first and on its last :data:`QUIET_SHARE`
    of samples, the smaller of the two (a record starts or ends with the table at rest), and the
    median over the records; 0 when nothing is still. Derived once per campaign (kept in its cache): every
    floor a diagnosis measures reads it.
    """
    cache = getattr(campaign, "_cache", None)
    if cache is None:
        return _acc_channel_noise(campaign)
    if "acc_channel_noise" not in cache:
        cache["acc_channel_noise"] = _acc_channel_noise(campaign)
    return cache["acc_channel_noise"]


def _acc_channel_noise(campaign) -> float:
    fv = [np.asarray(r.motion.acc, dtype=float) for r in campaign.free_vibration]
    fv = [a for a in fv if a.size > 1 and np.any(a != 0.0)]
    if fv:
        return float(math.sqrt(np.mean(np.concatenate([(a - a.mean()) ** 2 for a in fv]))))
    est = []
    for r in campaign.ground_motion:
        a = np.asarray(r.motion.acc, dtype=float)
        k = max(int(QUIET_SHARE * a.size), 50)
        if a.size < 2 * k:
            continue
        est.append(min(estimate_noise(a[:k]), estimate_noise(a[-k:])))
    return float(np.median(est)) if est else 0.0


@dataclass(frozen=True)
class ModelForm:
    """One correct integrator's conventions (``docs/explanation/diagnosis.md``, "The floor").

    Attributes
    ----------
    convention : str
        One of :data:`CONVENTIONS`.
    shift : float
        Delay of the input felt by the block behind its samples [samples].
    scale : float
        Amplitude factor of the input felt [-].
    rest_tol : float
        Rest rule [-].
    substep_factor : int
        Multiple of the library's substeps.
    acc_noise : float
        Noise of the acceleration channel [m/s^2]: the block felt the record minus a fresh draw of it.
    noise_seed : int
        Seed of that draw.
    """

    convention: str = "linear"
    shift: float = 0.0
    scale: float = 1.0
    rest_tol: float = REST_TOL
    substep_factor: int = 1
    acc_noise: float = 0.0
    noise_seed: int = 0

    @classmethod
    def draw(cls, rng: np.random.Generator, acc_noise: float = 0.0, family: str = "any") -> ModelForm:
        """A random integrator of ``family`` (:data:`FAMILIES`); ``rng`` makes it reproducible."""
        if family not in FAMILIES:
            raise ValueError(f"`family` must be one of {list(FAMILIES)}, got {family!r}")
        lam, solver = FAMILIES[family]
        lo, hi = (math.log(v) for v in REST_TOL_RANGE)
        held = lam >= 1.0 and rng.random() < 0.5
        shift = float(lam * rng.uniform(-SHIFT_SAMPLES, SHIFT_SAMPLES))
        scale = float(1.0 + lam * SCALE_SD * rng.standard_normal())
        rest_tol = float(math.exp(rng.uniform(lo, hi)))
        factor = int(SUBSTEP_FACTORS[int(rng.integers(len(SUBSTEP_FACTORS)))])
        return cls(
            convention="held" if held else "linear",
            shift=shift,
            scale=scale,
            rest_tol=rest_tol if solver else REST_TOL,
            substep_factor=factor if solver else 1,
            acc_noise=float(acc_noise),
            noise_seed=int(rng.integers(2**31)),
        )

    def describe(self) -> dict:
        return {
            "convention": self.convention,
            "shift_samples": round(self.shift, 4),
            "scale": round(self.scale, 6),
            "rest_tol": float(f"{self.rest_tol:.3g}"),
            "substep_factor": self.substep_factor,
            "acc_noise": self.acc_noise,
        }

    def felt(self, motion: GroundMotion, rng: np.random.Generator | None = None) -> GroundMotion:
        """The input the block felt, on a grid :data:`UPSAMPLE` times finer than ``motion``'s [m/s^2].

        Extra channels (a vertical acceleration) go through the same convention, timing and scale.
        """
        a = np.asarray(motion.acc, dtype=float)
        if self.acc_noise > 0.0 and rng is not None:
            a = a - rng.normal(0.0, self.acc_noise, a.size)
        n = a.size
        dt = motion.dt
        tf = np.arange((n - 1) * UPSAMPLE + 1) * (dt / UPSAMPLE) - self.shift * dt
        k = np.clip(np.floor(tf / dt + 1e-9).astype(np.int64), 0, n - 1)

        def fine(x: np.ndarray) -> np.ndarray:
            x = np.asarray(x, dtype=float)
            return self.scale * (x[k] if self.convention == "held" else np.interp(tf, np.arange(n) * dt, x))

        return GroundMotion(
            fine(a),
            dt / UPSAMPLE,
            motion.name,
            motion.provenance,
            motion.theta0,
            motion.theta_dot0,
            {key: fine(c) for key, c in motion.channels.items()},
        )

    def simulate(self, specimen, records: Sequence, effects: Sequence, settings: dict) -> list[np.ndarray | str]:
        """theta [rad] of each record on its own sample grid as this integrator produces it (or an error text)."""
        rng = np.random.default_rng(self.noise_seed)
        fine = [replace(r, motion=self.felt(r.motion, rng)) for r in records]
        sub = settings.get("substeps")
        base = (
            default_substeps(specimen.frequency_parameter, records[0].dt / UPSAMPLE)
            if not sub
            else max(1, math.ceil(int(sub) / UPSAMPLE))
        )
        run = {**settings, "rest_tol": self.rest_tol, "substeps": self.substep_factor * int(base)}
        out: list[np.ndarray | str] = []
        for rec, res in zip(records, simulate_records(specimen, fine, "housner", effects, run), strict=True):
            if isinstance(res, str):
                out.append(res)
            else:
                out.append(np.asarray(res.theta, dtype=float)[::UPSAMPLE][: rec.theta.size])
        return out
