"""Helpers shared by several test files: motions and engine variants built for the tests, the command run in a
subprocess."""

from __future__ import annotations

import functools
import html
import math
import re
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp

from housner import G, GroundMotion
from housner.engines.mujoco_engine import MujocoEngine


def windowed_sines(n: int, seed: int, *, freq=(1.0, 4.0), amp=(1.0, 4.0), scale: float = 1.0, centre=1.2, width=0.7):
    """``n`` sines [m/s^2] under a Gaussian window, 3 s at 500 Hz, named m0, m1, ...

    Frequency [Hz], amplitude (times ``scale``) and phase are drawn from
    ``default_rng(seed)``; the window is centred at ``centre`` s with half-width ``width`` s.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 3.0, 0.002)
    out = []
    for i in range(n):
        f, a, ph = rng.uniform(*freq), rng.uniform(*amp), rng.uniform(0, 2 * np.pi)
        acc = scale * a * np.sin(2 * np.pi * f * t + ph) * np.exp(-(((t - centre) / width) ** 2))
        out.append(GroundMotion(acc, 0.002, name=f"m{i}"))
    return out


class SoftGroundMujoco(MujocoEngine):
    """MuJoCo with the ground at its default solref and solimp: the first tuned contact, about 40 times too soft."""

    def mjcf(self, specimen):
        xml = super().mjcf(specimen)
        start = xml.index('<geom name="ground"')
        end = xml.index("/>", start)
        return xml[:start] + xml[start:end].split(" solref=")[0] + xml[end:]


def reference_solve_ivp(acc, dt, alpha, p, r, rest_tol=1e-6, rtol=1e-12, atol=1e-14):
    """Housner's model with scipy's DOP853, restarted at every impact (the tests' reference, the benchmark's baseline).

    Written independently of housner.model: events for impact, overturn and peaks,
    the same uplift and rest rules. Returns (theta_max [rad], overturned, impact times [s]).
    """
    ag = np.asarray(acc) / G
    n = ag.size
    t_end = (n - 1) * dt
    tan_a = math.tan(alpha)
    e_rest = math.cos(alpha - rest_tol * alpha) - math.cos(alpha)

    def ug(t):
        k = min(int(t / dt), n - 2)
        return ag[k] + (ag[k + 1] - ag[k]) * (t / dt - k)

    def rhs(t, y, s):
        d = s * alpha - y[0]
        return [y[1], -p * p * (math.sin(d) + ug(t) * math.cos(d))]

    def impact(t, y, s):
        return y[0]

    def overturn(t, y, s):
        return abs(y[0]) - math.pi / 2

    def peak(t, y, s):
        return y[1]

    impact.terminal = True
    overturn.terminal = True
    t, th, thd, s = 0.0, 0.0, 0.0, 1.0
    at_rest, theta_max, impacts = True, 0.0, []
    while t < t_end:
        if at_rest:
            lift = _uplift(ag, dt, t, tan_a, ug)
            if lift is None:
                break
            t, s = lift
            th, thd, at_rest = 0.0, 0.0, False
        impact.direction = -s
        sol = solve_ivp(
            rhs,
            (t, t_end),
            [th, thd],
            method="DOP853",
            rtol=rtol,
            atol=atol,
            events=[impact, overturn, peak],
            args=(s,),
        )
        theta_max = max(theta_max, np.max(np.abs(sol.y[0])))
        if sol.t_events[2].size:
            theta_max = max(theta_max, np.max(np.abs(sol.y_events[2][:, 0])))
        if sol.t_events[1].size:
            return math.pi / 2, True, np.array(impacts)
        if not sol.t_events[0].size:
            break
        t = sol.t_events[0][0]
        impacts.append(t)
        th, thd, s = 0.0, math.sqrt(r) * sol.y_events[0][0][1], -s
        if thd * thd / (2 * p * p) < e_rest:
            at_rest, thd = True, 0.0
    return theta_max, False, np.array(impacts)


def _uplift(ag: np.ndarray, dt: float, t: float, tan_a: float, ug) -> tuple[float, float] | None:
    """(time [s], side) of the first uplift at or after ``t``: |ug''| / g reaches tan(alpha) on the linear interpolant.

    theta > 0 (side +1) when ug'' < -g tan(alpha). None when it never does. Vectorised: a
    block at rest for long stretches must not cost the baseline a Python loop per sample.
    """
    now = ug(t)
    if abs(now) > tan_a:
        return t, (1.0 if now < 0 else -1.0)
    k0 = min(int(t / dt), ag.size - 2)
    beyond = np.flatnonzero(np.abs(ag[k0 + 1 :]) > tan_a)
    if beyond.size == 0:
        return None
    k = k0 + int(beyond[0])  # the crossing lies between samples k and k + 1
    sgn = 1.0 if ag[k + 1] < 0 else -1.0
    b0, b1 = sgn * ag[k], sgn * ag[k + 1]
    return max(t, k * dt + dt * (-tan_a - b0) / (b1 - b0)), sgn


@functools.cache
def engine_unavailable(name: str) -> str | None:
    """Why the registered engine ``name`` cannot run here (its own one-line message), or None when it can.

    The engine is instantiated, which imports its package: a missing package and one that is installed
    but cannot load (OpenSees without Debian's BLAS and LAPACK) both give the engine's own message,
    which names the install.
    """
    from housner.engines.base import get_engine
    from housner.errors import EngineUnavailable

    try:
        get_engine(name)
    except EngineUnavailable as e:
        return str(e)
    except ImportError as e:  # an adapter still being written
        return f"engine {name!r} does not import: {e}"
    return None


def optional_engine(name: str):
    """``name`` as a pytest parameter, skipped with the engine's own message when it cannot run here."""
    import pytest

    why = engine_unavailable(name)
    return pytest.param(name, marks=pytest.mark.skipif(why is not None, reason=why or ""))


#: Engines of the package besides the analytic one: MuJoCo and PyBullet are core dependencies, the rest extras.
OTHER_ENGINE_NAMES = ("mujoco", "pybullet", "dart", "opensees", "drake")
_CORE = ("mujoco", "pybullet")


def installed_engines() -> list[str]:
    """The names of :data:`OTHER_ENGINE_NAMES` that can run here."""
    return [n for n in OTHER_ENGINE_NAMES if n in _CORE or engine_unavailable(n) is None]


#: The engines the cross-engine tests run besides the analytic one (optional ones skip when absent).
OTHER_ENGINES = [n if n in _CORE else optional_engine(n) for n in OTHER_ENGINE_NAMES]


def assert_overturns_and_holds(engine, specimen, *, holds: bool = True) -> None:
    """A -3 g tan(alpha) push from 0.1 s overturns the block to +pi/2, with an uplift and an overturn time.

    ``holds``: theta also stays at +pi/2 from 1 ms after the overturn time to the end of the record.
    """
    import pytest

    t = np.arange(0, 3.0, 1e-3)
    acc = np.where(t > 0.1, -3.0 * G * math.tan(specimen.alpha), 0.0)
    res = engine.simulate(specimen, GroundMotion(acc, 1e-3, name="push"))
    assert res.overturned and res.theta[-1] == pytest.approx(math.pi / 2)
    if holds:
        assert np.all(res.theta[res.t >= res.overturn_time + 1e-3] == pytest.approx(math.pi / 2))
    assert 0.1 < res.overturn_time < 3.0 and math.isfinite(res.uplift_time)


def assert_pulses_follow_the_analytic_model(engine, specimen, *, rel: float, same_impacts: bool) -> None:
    """The tuner's three one-sine pulses: same overturn verdict, theta_max within ``rel``, and (when
    ``same_impacts``) the same impact count as the analytic model."""
    import pytest

    from housner.engines.base import get_engine
    from housner.engines.tuning import pulse_motions

    ref = get_engine("housner")
    for m in pulse_motions(specimen):
        a, d = ref.simulate(specimen, m), engine.simulate(specimen, m)
        assert d.overturned == a.overturned, m.name
        assert d.theta_max == pytest.approx(a.theta_max, rel=rel), m.name
        if same_impacts:
            assert d.n_impacts == a.n_impacts, m.name


def page_text(page: str) -> str:
    """An HTML page's visible text (figures and tags removed, entities decoded, whitespace collapsed)."""
    body = re.sub(r'src="data:image/png;base64,[^"]*"', "", page)
    return html.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", body)))


def page_section(page: str, sid: str) -> str:
    """The HTML of a page's ``<section id="sid">``."""
    i = page.index(f'<section id="{sid}">')
    return page[i : page.index("</section>", i)]


def housner_command(*args: str) -> list[str]:
    """The command line of ``housner ARGS`` in a subprocess: this interpreter, ``-m housner.cli``."""
    return [sys.executable, "-m", "housner.cli", *args]


def run_command(out, engines: str, n_motions: int, *options: str, scenario: str = "elcentro") -> list[str]:
    """The command line of ``housner run SCENARIO --engines ENGINES --n-motions N_MOTIONS --out OUT OPTIONS``."""
    return housner_command(
        "run", scenario, "--engines", engines, "--n-motions", str(n_motions), "--out", str(out), *options
    )


def run_housner(*args: str, timeout: float, **kwargs) -> subprocess.CompletedProcess:
    """``housner ARGS`` run in a subprocess (``kwargs`` to :func:`subprocess.run`: env, cwd), its output as text."""
    return subprocess.run(housner_command(*args), capture_output=True, text=True, timeout=timeout, **kwargs)


def assert_strict_json_fixed_point(result, fresh, indent: int = 2):
    """A diagnosis result as its file is written (strict JSON): ``fresh`` (the result computed again) writes the
    same text as ``result``, and read back it writes that text again and reads back equal to itself (a number
    without a finite value is written null and read as NaN: only a value read once is a fixed point). Returns the
    value read."""
    import json

    def text(value) -> str:
        return json.dumps(value.to_json(), indent=indent, allow_nan=False)

    cls = type(fresh)
    assert text(fresh) == text(result)  # the file is the value's
    read = cls.from_json(json.loads(text(fresh)))
    assert text(read) == text(fresh)
    assert cls.from_json(json.loads(text(read))) == read
    return read
