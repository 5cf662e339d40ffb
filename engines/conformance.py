"""The conformance check every engine passes: rest, symmetry, determinism, bounds, sign and period.

``check_engine(engine)`` runs a handful of short records (a few seconds of simulated time in all), made
dimensionless with the specimen's p and g tan(alpha) so that the check means the same for any block, and
returns a :class:`ConformanceReport` with one :class:`CheckResult` per check (``at_rest``,
``mirror_symmetry``, ``deterministic``, ``finite_and_bounded``, ``sign_and_overturn``,
``free_vibration_period``); it does not raise. ``assert_conforms(engine)`` runs it and raises
``AssertionError`` with the readable list of failures, for tests. Each check's record and tolerance, and
why, are in ``docs/explanation/engines.md`` ("The conformance check").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from housner.engines.base import Engine, get_engine
from housner.engines.measures import free_rocking_quarter_period, parabolic_peak
from housner.engines.tuning import pulse_motions
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = ["CheckResult", "ConformanceReport", "assert_conforms", "check_engine"]

#: |theta| / alpha allowed at rest under 0.9 g tan(alpha) [-] (docs/explanation/engines.md, "The conformance check").
REST_TOL = 1e-3
#: Fraction of g tan(alpha) applied in the rest check [-].
REST_LEVEL = 0.9
#: Mirror-symmetry tolerance, a fraction of theta_max [-].
MIRROR_RTOL = 0.01
#: Relative tolerance on the free-vibration durations [-].
PERIOD_RTOL = 0.01
#: Release amplitude of the period check, theta0 / alpha [-].
PERIOD_AMPLITUDE = 0.5
#: The mirror pulse: (omega_p / p, a_p / (g tan alpha)) [-].
MIRROR_PULSE = (8.0, 5.0)
#: Sample step of the check's records [s].
DT = 0.001


@dataclass(frozen=True)
class CheckResult:
    """One conformance check.

    Attributes
    ----------
    name : str
        Check name (``at_rest``, ``mirror_symmetry``, ...).
    passed : bool
    value : float
        The measured figure (its meaning is in ``detail``).
    tolerance : float
        The bound it is compared with.
    detail : str
        One readable sentence: what was measured and against what.
    """

    name: str
    passed: bool
    value: float
    tolerance: float
    detail: str


@dataclass
class ConformanceReport:
    """All checks of one engine on one specimen.

    Attributes
    ----------
    engine : str
        Engine name and settings (its repr).
    specimen : str
        Specimen name.
    checks : list of CheckResult
    """

    engine: str
    specimen: str
    checks: list[CheckResult] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when every check passed."""
        return all(c.passed for c in self.checks)

    @property
    def failures(self) -> list[str]:
        """One line per failed check: ``name: detail``."""
        return [f"{c.name}: {c.detail}" for c in self.checks if not c.passed]

    def __str__(self) -> str:
        head = f"conformance of {self.engine} on {self.specimen}: {'OK' if self.ok else 'FAILED'}"
        lines = [head] + [f"  [{'ok' if c.passed else 'FAIL'}] {c.name}: {c.detail}" for c in self.checks]
        return "\n".join(lines)

    def assert_ok(self) -> None:
        """Raise ``AssertionError`` listing the failed checks, if any."""
        if not self.ok:
            raise AssertionError(
                f"engine {self.engine} fails {len(self.failures)} conformance check(s) on {self.specimen}:\n  "
                + "\n  ".join(self.failures)
            )


# ----------------------------------------------------------------------------
def _ramp_hold(specimen: Specimen, level: float, ramp: float, duration: float, name: str) -> GroundMotion:
    """ug'' rising as a half-cosine over ``ramp`` [s] to ``level`` g tan(alpha), then held; ``duration`` [s]."""
    n = int(math.ceil(duration / DT)) + 1
    t = np.arange(n) * DT
    shape = np.where(t < ramp, 0.5 * (1.0 - np.cos(math.pi * t / ramp)), 1.0)
    acc = level * specimen.uplift_acceleration * shape
    return GroundMotion(acc, DT, name=name, provenance="housner.engines.conformance")


def _slow_sine(specimen: Specimen, level: float, period: float) -> GroundMotion:
    n = int(math.ceil(period / DT)) + 1
    t = np.arange(n) * DT
    acc = level * specimen.uplift_acceleration * np.sin(2.0 * math.pi * t / period)
    return GroundMotion(acc, DT, name=f"slow sine {level:g} g tan(alpha)", provenance="housner.engines.conformance")


def _mirror(motion: GroundMotion) -> GroundMotion:
    return GroundMotion(-motion.acc, motion.dt, name=f"{motion.name} (mirrored)", provenance=motion.provenance)


def _peak_between(t: np.ndarray, theta: np.ndarray, t0: float, t1: float) -> float:
    """Largest |theta| [rad] strictly between t0 and t1, refined by a parabola through its neighbours."""
    sel = np.flatnonzero((t > t0) & (t < t1))
    if sel.size == 0:
        return math.nan
    i = int(sel[np.argmax(np.abs(theta[sel]))])
    return parabolic_peak(np.abs(theta), i)


def _bounded(resp: Response, motion: GroundMotion) -> str:
    """Empty string if the response is finite, on the grid and within +-pi/2; else what is wrong."""
    if resp.theta.shape != (motion.n,) or resp.t.shape != (motion.n,):
        return f"{motion.name!r}: theta has shape {resp.theta.shape}, expected ({motion.n},)"
    if not np.allclose(resp.t, motion.t, rtol=0, atol=1e-9 * max(1.0, motion.duration)):
        return f"{motion.name!r}: t is not the motion's sample grid"
    for key in ("theta", "theta_dot"):
        arr = getattr(resp, key)
        if not np.all(np.isfinite(arr)):
            return f"{motion.name!r}: {key} is not finite"
    if not math.isfinite(resp.theta_max):
        return f"{motion.name!r}: theta_max is not finite"
    worst = float(np.max(np.abs(resp.theta)))
    if worst > math.pi / 2 + 1e-12:
        return f"{motion.name!r}: |theta| reaches {worst:.6g} rad > pi/2"
    return ""


def check_engine(engine: Engine | str, specimen: Specimen | None = None) -> ConformanceReport:
    """Run the conformance checks on an engine.

    Parameters
    ----------
    engine : Engine or str
        An engine instance, or a registry name (instantiated with its defaults).
    specimen : Specimen, optional
        Default: ``Specimen.bachmann2017()``.

    Returns
    -------
    ConformanceReport
        ``.ok``, ``.failures`` and one :class:`CheckResult` per check; call
        ``.assert_ok()`` (or use :func:`assert_conforms`) to raise on failure.
    """
    if isinstance(engine, str):
        engine = get_engine(engine)
    if not isinstance(engine, Engine):
        raise TypeError(f"`engine` must be an Engine or a registry name, got {type(engine).__name__}")
    specimen = Specimen.bachmann2017() if specimen is None else specimen
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    report = ConformanceReport(engine=repr(engine), specimen=specimen.name)
    seen: list[tuple[Response, GroundMotion]] = []

    def run(motion: GroundMotion) -> Response:
        resp = engine.simulate(specimen, motion)
        seen.append((resp, motion))
        return resp

    report.checks.append(_at_rest(run, specimen))
    report.checks.extend(_mirror_and_determinism(run, specimen))
    report.checks.append(_sign_and_overturn(run, specimen))
    report.checks.append(_free_vibration_period(run, specimen))
    # (d) finite, on the grid and bounded: every response above
    bad = [msg for msg in (_bounded(r, m) for r, m in seen) if msg]
    detail = f"all {len(seen)} responses finite, on the sample grid, |theta| <= pi/2" if not bad else "; ".join(bad)
    report.checks.append(CheckResult("finite_and_bounded", not bad, float(len(bad)), 0.0, detail))
    return report


def _at_rest(run, specimen: Specimen) -> CheckResult:
    """(a) At rest below the uplift threshold: ramps to +-REST_LEVEL g tan(alpha) and a slow sine."""
    alpha, p = specimen.alpha, specimen.p
    rest_motions = [
        _ramp_hold(specimen, REST_LEVEL, 1.0 / p, 8.0 / p, f"ramp to +{REST_LEVEL} g tan(alpha)"),
        _ramp_hold(specimen, -REST_LEVEL, 1.0 / p, 8.0 / p, f"ramp to -{REST_LEVEL} g tan(alpha)"),
        _slow_sine(specimen, REST_LEVEL, 8.0 / p),
    ]
    worst, where = 0.0, ""
    for m in rest_motions:
        resp = run(m)
        v = math.inf if resp.overturned else float(np.max(np.abs(resp.theta))) / alpha
        if v >= worst:
            worst, where = v, m.name
    return CheckResult(
        "at_rest",
        worst < REST_TOL,
        worst,
        REST_TOL,
        f"max |theta|/alpha = {worst:.3g} under {REST_LEVEL} g tan(alpha) (worst: {where}); "
        f"must stay below {REST_TOL:g}",
    )


def _mirror_and_determinism(run, specimen: Specimen) -> list[CheckResult]:
    """(b) Mirror symmetry and (c) determinism on one pulse."""
    alpha, p = specimen.alpha, specimen.p
    (pulse,) = pulse_motions(specimen, pulses=(MIRROR_PULSE,), dt=DT)
    pulse = pulse.with_duration(2.0 * math.pi / (MIRROR_PULSE[0] * p) + 4.0 / p)
    a = run(pulse)
    b = run(_mirror(pulse))
    scale = max(a.theta_max, b.theta_max)
    if scale > 0 and a.theta.shape == b.theta.shape:
        asym = float(np.max(np.abs(a.theta + b.theta))) / scale
    else:
        asym = math.inf
    mirror = CheckResult(
        "mirror_symmetry",
        asym <= MIRROR_RTOL,
        asym,
        MIRROR_RTOL,
        f"max |theta(t) + theta_mirrored(t)| = {asym:.3g} theta_max on {pulse.name!r} "
        f"(theta_max {a.theta_max / alpha:.4f} alpha, {a.n_impacts} impacts); must be <= {MIRROR_RTOL:g}",
    )
    a2 = run(pulse)
    same = (
        np.array_equal(a.theta, a2.theta)
        and np.array_equal(a.theta_dot, a2.theta_dot)
        and np.array_equal(a.impact_times, a2.impact_times)
        and a.theta_max == a2.theta_max
    )
    diff = float(np.max(np.abs(a.theta - a2.theta))) if a.theta.shape == a2.theta.shape else math.inf
    how = "are identical" if same else f"differ (max |dtheta| = {diff:.3g} rad)"
    return [mirror, CheckResult("deterministic", bool(same), diff, 0.0, f"two runs of {pulse.name!r} " + how)]


def _sign_and_overturn(run, specimen: Specimen) -> CheckResult:
    """Sign convention and overturning: a ground acceleration of -3 g tan(alpha) lifts to theta > 0 and overturns."""
    alpha, p = specimen.alpha, specimen.p
    resp = run(_ramp_hold(specimen, -3.0, 0.5 / p, 10.0 / p, "ramp to -3 g tan(alpha)"))
    moved = np.flatnonzero(np.abs(resp.theta) > REST_TOL * alpha)
    first_sign = float(np.sign(resp.theta[moved[0]])) if moved.size else 0.0
    problems = []
    if first_sign <= 0:
        problems.append("the block did not lift to theta > 0" if moved.size else "the block did not move")
    if not resp.overturned:
        problems.append(f"it did not overturn (theta_max {resp.theta_max / alpha:.3g} alpha)")
    if not math.isclose(resp.theta[-1], math.pi / 2, rel_tol=0, abs_tol=1e-9):
        problems.append(f"it ends at theta = {resp.theta[-1]:.6g} rad, not +pi/2")
    if not math.isfinite(resp.overturn_time):
        problems.append("no overturn time")
    return CheckResult(
        "sign_and_overturn",
        not problems,
        first_sign,
        1.0,
        "ground acceleration -3 g tan(alpha): "
        + ("; ".join(problems) if problems else f"lifts to theta > 0 and overturns at {resp.overturn_time:.4g} s"),
    )


def _free_vibration_period(run, specimen: Specimen) -> CheckResult:
    """(e) Free-vibration period against the exact quadrature: the first impact and the next half-cycle."""
    alpha = specimen.alpha
    th0 = PERIOD_AMPLITUDE * alpha
    tq = free_rocking_quarter_period(specimen, th0)
    fv = GroundMotion.free_vibration(th0, 3.2 * tq + 0.05, dt=DT, name=f"free vibration {PERIOD_AMPLITUDE:g} alpha")
    resp = run(fv)
    imp = resp.impact_times
    if imp.size < 2:
        detail = f"release at {PERIOD_AMPLITUDE:g} alpha: only {imp.size} impact(s) in {fv.duration:.3g} s, expected 2"
        return CheckResult("free_vibration_period", False, math.inf, PERIOD_RTOL, detail)
    e1 = imp[0] / tq - 1.0
    th1 = _peak_between(resp.t, resp.theta, imp[0], imp[1])
    half = 2.0 * free_rocking_quarter_period(specimen, th1)
    e2 = (imp[1] - imp[0]) / half - 1.0
    err = max(abs(e1), abs(e2))
    detail = (
        f"release at {PERIOD_AMPLITUDE:g} alpha: first impact at {imp[0]:.5f} s vs exact {tq:.5f} s ({e1:+.3%}); "
        f"next half-cycle {imp[1] - imp[0]:.5f} s vs exact {half:.5f} s for its peak {th1 / alpha:.4f} alpha "
        f"({e2:+.3%}); must be within {PERIOD_RTOL:.0%}"
    )
    return CheckResult("free_vibration_period", err <= PERIOD_RTOL, err, PERIOD_RTOL, detail)


def assert_conforms(engine: Engine | str, specimen: Specimen | None = None) -> ConformanceReport:
    """:func:`check_engine`, raising ``AssertionError`` with the list of failures; returns the report if all pass."""
    report = check_engine(engine, specimen)
    report.assert_ok()
    return report
