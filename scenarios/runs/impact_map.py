"""An engine's departure from Housner's model where it happens: at each impact and in each flight (its "maps").

:func:`measure_maps` releases the block from rest at a grid of amplitudes (alternately toward +x and -x, no
ground motion), runs the engine, and measures every impact and every flight between two impacts against
Housner's model, each flight fitted from theta alone with Housner's energy integral. The result,
:class:`EngineMaps`, holds the raw points and the tables binned by the normalised impact speed
x = |w-| / (p alpha): the impact map (the fraction of Housner's r the engine keeps,
:meth:`EngineMaps.impact_table`) and the flight map (the loss rate c [1/s] of dE/dt = -c w^2,
:meth:`EngineMaps.flight_table`), which the effect ``measured_maps`` (:mod:`housner.effects.measured`)
composes into the analytic kernel. The definitions, the method and why it is so are in
``docs/explanation/engine-maps.md``.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy import optimize

from housner._values import same
from housner.engines.base import engine_spec, get_engine
from housner.free_vibration.closed_forms import half_cycle_time
from housner.motion import GroundMotion
from housner.scenarios.execution.run_meta import SpecimenFacts
from housner.specimen import Specimen

__all__ = [
    "AMPLITUDES",
    "DT",
    "ENGINE_ALIASES",
    "EngineMaps",
    "X_EDGES",
    "engine_registry_name",
    "measure_maps",
]

#: The seed specimen (Bachmann et al. 2017).
SEED = Specimen.bachmann2017()

#: Release amplitudes theta0 / alpha [-]: the first impact's x = sqrt(2 a - a^2) (small alpha) runs from 0.049
#: (a = 0.0012) to 0.995 (a = 0.9), each release's impacts then step down by sqrt(r_housner) = 0.973. Below
#: x ~ 0.045 a half-cycle (2 sqrt(2 a) / p = 18 ms) holds too few 1 ms samples for the guards and two fits.
AMPLITUDES = (0.0012, 0.002, 0.003, 0.006, 0.012, 0.025, 0.05, 0.1, 0.2, 0.45, 0.9)
#: Sample interval [s] (docs/explanation/engine-maps.md, "How they are measured").
DT = 1e-3
#: Impacts measured per release.
N_IMPACTS = 12
#: Shortest guard [s] either side of an impact whose samples are the contact's: MuJoCo's and PyBullet's
#: energy settles within 3-4 ms of the sign change, OpenSees' contact springs ring for about as long.
GUARD_S = 3e-3
#: Longest flight window [s] fitted on each side of an impact.
WINDOW_S = 15e-3
#: Fewest flight samples on a side for its fit.
MIN_FIT = 3
#: Departure of theta from a flight beyond which a sample is the contact's, as a fraction [-] of a sample's travel
#: at the impact speed: at an impact w drops by 1 - sqrt(r_housner) = 2.7 % (seed), so a contact that lasts a
#: sample moves theta off the flight by ~1e-2 of that travel; 2e-4 is fifty times finer.
DEPART_FRACTION = 2e-4
#: A sign change is an impact when the half-cycle before it peaked above this fraction [-] of the smallest peak
#: the release is expected to reach (Housner's decay over the impacts measured).
SWING_TOL = 0.1
#: Bin edges of x [-]: ten per decade from 0.025 to 1.26.
X_EDGES = 10.0 ** np.arange(-1.6, 0.15, 0.1)
#: Names accepted for a registered engine.
ENGINE_ALIASES = {"analytic": "housner"}

# Gauss-Legendre nodes on [0, 1] for the flight time from theta to 0 (smooth integrand, 8 nodes: ~1e-12).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_GL_X, _GL_W = 0.5 * (_GL_X + 1.0), 0.5 * _GL_W

_IMPACT_COLUMNS = (
    "release",
    "k",
    "t_s",
    "w_pre_rad_s",
    "w_post_rad_s",
    "x",
    "r",
    "ratio_to_housner",
    "contact_s",
    "contact_delay_s",
)
_FLIGHT_COLUMNS = (
    "release",
    "k",
    "x",
    "e_start_rad2_s2",
    "e_end_rad2_s2",
    "energy_change",
    "c_per_s",
    "half_period_s",
    "housner_half_period_s",
    "period_drift",
)


def engine_registry_name(name: str) -> str:
    """The registry name of ``name`` (``analytic`` is ``housner``); unknown names list the choices."""
    name = ENGINE_ALIASES.get(name, name)
    return engine_spec(name).name


@dataclass(frozen=True, eq=False)
class EngineMaps:
    """An engine's impact and flight maps against Housner's model (``docs/explanation/engine-maps.md``).

    Parameters
    ----------
    engine : str
        Registry name.
    label : str
        The engine as messages name it.
    settings : dict
        The engine's settings.
    version : str
        Version of the engine's package.
    specimen : SpecimenFacts
        ``Specimen.describe()`` of the block.
    dt_s : float
        Sample interval [s].
    amplitudes : tuple of float
        Release amplitudes theta0 / alpha [-].
    r_housner : float
        Housner's kinetic-energy ratio of the specimen [-].
    impacts : dict
        Binned impact table: ``x`` [-], ``ratio_median`` [-], ``ratio_spread`` [-] (IQR / 1.349 from 4
        points, else the standard deviation), ``n``, ``contact_median_s`` [s], ``contact_delay_median_s`` [s],
        and each bin's ``x_low`` and ``x_high``.
    flights : dict
        Binned flight table: ``x`` [-], ``c_median_per_s`` [1/s], ``c_spread_per_s`` [1/s], ``n``,
        ``energy_change_median`` [-] (per flight), ``period_drift_median`` [-], ``x_low``, ``x_high``.
    impact_points, flight_points : dict
        The raw points, one column per key (units in the keys).
    wall_s : float
        Wall time of the measurement [s].
    """

    engine: str
    label: str
    settings: dict
    version: str
    specimen: SpecimenFacts
    dt_s: float
    amplitudes: tuple
    r_housner: float
    impacts: dict
    flights: dict
    impact_points: dict
    flight_points: dict
    wall_s: float = math.nan
    method: dict = field(default_factory=dict)

    def impact_table(self) -> tuple[np.ndarray, np.ndarray]:
        """(x [-], ratio_to_housner [-]) per bin: the impact law r' = r_housner * ratio(x), x = |w-| / (p alpha)."""
        return np.asarray(self.impacts["x"], float), np.asarray(self.impacts["ratio_median"], float)

    def flight_table(self) -> tuple[np.ndarray, np.ndarray]:
        """(x [-], c [1/s]) per bin: the flight moment -c(x_E) w, x_E = sqrt(2 E) / (p alpha)."""
        return np.asarray(self.flights["x"], float), np.asarray(self.flights["c_median_per_s"], float)

    def at(self, x: float) -> dict:
        """The tables read at x [-] (log-linear interpolation, end values held): ratio, its spread, c, contact."""
        columns = {
            "ratio": (self.impacts, "ratio_median"),
            "ratio_spread": (self.impacts, "ratio_spread"),
            "contact_s": (self.impacts, "contact_median_s"),
            "c_per_s": (self.flights, "c_median_per_s"),
            "period_drift": (self.flights, "period_drift_median"),
        }
        out = {}
        for key, (table, col) in columns.items():
            xs, ys = np.asarray(table["x"], float), np.asarray(table[col], float)
            ok = np.isfinite(xs) & np.isfinite(ys)
            out[key] = float(np.interp(math.log(x), np.log(xs[ok]), ys[ok])) if ok.any() else math.nan
        return out

    def __eq__(self, other: object) -> bool:
        """Equal maps write the same data (a bin without a value, NaN, equals NaN; a tuple its JSON list)."""
        if type(other) is not type(self):
            return NotImplemented
        return same(self.to_dict(), other.to_dict())

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict:
        """Plain data (JSON-ready)."""
        d = asdict(self)
        d["specimen"] = self.specimen.to_json()
        d["amplitudes_over_alpha"] = list(d.pop("amplitudes"))
        d["format"] = "housner-impact-maps/1"
        return _plain(d)

    def to_json(self) -> str:
        """The maps as JSON text (units in the keys)."""
        return json.dumps(self.to_dict(), indent=1, allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> EngineMaps:
        """Maps from :meth:`to_json`'s text; ValueError naming what is missing."""
        try:
            d = json.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"impact maps: not JSON ({e})") from None
        return cls.from_dict(d)

    @classmethod
    def from_dict(cls, d: Mapping) -> EngineMaps:
        """Maps from :meth:`to_dict`'s data (as read from JSON); ValueError naming what is missing."""
        if isinstance(d, EngineMaps):
            return d
        if not isinstance(d, Mapping) or d.get("format") != "housner-impact-maps/1":
            raise ValueError("impact maps: not a housner impact-maps file (format 'housner-impact-maps/1')")
        d = dict(d)
        d.pop("format")
        d["amplitudes"] = tuple(d.pop("amplitudes_over_alpha"))
        d["specimen"] = SpecimenFacts.from_json(d.get("specimen"))
        # a file that writes a missing number as null (an explanation's, housner explain --json): NaN again
        for key in ("impacts", "flights", "impact_points", "flight_points"):
            if isinstance(d.get(key), Mapping):
                d[key] = {k: _nan_for_null(v) for k, v in d[key].items()}
        for key in ("dt_s", "r_housner", "wall_s"):
            if key in d and d[key] is None:
                d[key] = math.nan
        try:
            return cls(**d)
        except TypeError as e:
            raise ValueError(f"impact maps: {e}") from None

    def summary(self, xs: Sequence[float] = (0.05, 0.3, 0.9)) -> str:
        """A short table: the maps read at ``xs``, and the counts."""
        lines = [
            f"{self.label} ({self.engine} {self.version}): {len(self.impact_points['x'])} impacts, "
            f"{len(self.flight_points['x'])} flights, {self.wall_s:.1f} s"
        ]
        lines.append("      x   r/r_housner  spread     c [1/s]   drift/half-period  contact [ms]")
        for x in xs:
            v = self.at(x)
            lines.append(
                f"  {x:5.2f}   {v['ratio']:9.4f}  {v['ratio_spread']:7.4f}  {v['c_per_s']:+10.2e}"
                f"   {v['period_drift']:+10.2e}        {1e3 * v['contact_s']:5.1f}"
            )
        return "\n".join(lines)


def _nan_for_null(column):
    """A column of numbers read from JSON, null (a missing number) as NaN."""
    return [math.nan if v is None else v for v in column] if isinstance(column, list) else column


def _plain(v):
    """numpy scalars and arrays, tuples, as plain JSON types."""
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_plain(x) for x in v]
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        return float(v)
    return v


# ----------------------------------------------------------------------------
# one release


def _potential(theta: np.ndarray, alpha: float, p: float) -> np.ndarray:
    """U [rad^2/s^2]: p^2 (cos(alpha - |theta|) - cos(alpha))."""
    return p * p * (np.cos(alpha - np.abs(theta)) - math.cos(alpha))


def _flight_times(theta: np.ndarray, e: float, alpha: float, p: float) -> tuple[np.ndarray, np.ndarray]:
    """Housner's flight time [s] between theta = 0 and each |theta| at energy e [rad^2/s^2], and |w| there [rad/s].

    tau(theta) = int_0^|theta| dth / sqrt(2 (e - U(th))); the integrand is smooth while e > U(|theta|)
    (the window never reaches the peak), so 8 Gauss-Legendre nodes give it to ~1e-12.
    """
    th = np.abs(theta)[:, None] * _GL_X[None, :]
    d = 2.0 * (e - _potential(th, alpha, p))
    tau = np.abs(theta) * (_GL_W[None, :] / np.sqrt(np.maximum(d, 1e-300))).sum(axis=1)
    return tau, np.sqrt(np.maximum(2.0 * (e - _potential(theta, alpha, p)), 0.0))


def _crossings(theta: np.ndarray, tol: float) -> np.ndarray:
    """Index i of each sign change between samples i and i+1 after a half-cycle that peaked above ``tol`` [rad]."""
    sgn = np.sign(theta)
    nz = np.flatnonzero(sgn != 0)
    if nz.size < 2:
        return np.empty(0, dtype=int)
    change = np.flatnonzero(sgn[nz[1:]] != sgn[nz[:-1]])
    if change.size == 0:
        return np.empty(0, dtype=int)
    starts = np.concatenate(([nz[0]], nz[change + 1]))
    seg_max = np.maximum.reduceat(np.abs(theta), starts)[:-1]
    return nz[change[seg_max > tol]]


@dataclass
class _Side:
    """One side's flight fit around an impact: its energy, when it meets theta = 0, the window's mean time, the
    contact's edge."""

    e: float  # energy of the flight [rad^2/s^2]
    t_zero: float  # when the flight reaches (before the impact) or leaves (after it) theta = 0 [s]
    t_window: float  # mean time of the window's samples [s]
    edge: int  # the sample nearest the impact on the flight


def _fit_flight(t: np.ndarray, theta: np.ndarray, direction: int, alpha: float, p: float, dt: float):
    """Housner's flight through the samples (t, theta) of one side: (energy, t_zero, rms [rad]) or None.

    The flight meets theta = 0 at t_zero and passes |theta| at t_zero + direction * tau(|theta|; E);
    least squares on the residuals w (t - t_model), i.e. in theta, over (t_zero, log(E - U_max)).
    """
    u_max = float(_potential(np.max(np.abs(theta)), alpha, p))
    w_fd = np.abs(np.gradient(theta, dt))
    e0 = float(np.median(0.5 * w_fd**2 + _potential(theta, alpha, p)))
    s0 = math.log(max(e0 - u_max, 1e-6 * e0))

    def residual(q):
        e = u_max + math.exp(q[1])
        tau, w = _flight_times(theta, e, alpha, p)
        return w * (t - q[0] - direction * tau)

    tau0, _ = _flight_times(theta, u_max + math.exp(s0), alpha, p)
    q0 = np.array([float(np.median(t - direction * tau0)), s0])
    try:
        sol = optimize.least_squares(residual, q0, x_scale=np.array([dt, 1.0]), xtol=1e-14, ftol=1e-14, gtol=1e-14)
    except ValueError:
        return None
    if not sol.success and sol.status <= 0:
        return None
    res = sol.fun
    return u_max + math.exp(sol.x[1]), float(sol.x[0]), float(np.sqrt(np.mean(res * res)))


def _fit_side(t, theta, i_c, bound, direction, dt, alpha, p) -> _Side | None:
    """Fit one side of the impact whose sign change lies between samples i_c and i_c + 1.

    ``direction`` is -1 for the flight before the impact, +1 after; ``bound`` the sample index of the
    neighbouring impact (or the record's start or end) that limits the flight.
    """
    first = i_c if direction < 0 else i_c + 1  # the sample nearest the impact on this side
    span = abs(bound - first)
    guard = int(round(GUARD_S / dt))
    for attempt in range(3):  # widen the guard to the contact as measured, twice at most
        win = min(int(round(WINDOW_S / dt)), span // 3 - guard)
        if win < MIN_FIT:
            return None
        idx = first + direction * np.arange(guard, guard + win)
        fit = _fit_flight(t[idx], theta[idx], direction, alpha, p, dt)
        if fit is None:
            return None
        e, t_zero, rms = fit
        # the contact: the samples off the flight by more than the tolerance, walking out from the impact
        near = first + direction * np.arange(guard + win)
        tau, w = _flight_times(theta[near], e, alpha, p)
        w_c = math.sqrt(2.0 * e)
        tol = max(4.0 * rms, DEPART_FRACTION * w_c * dt)
        on = np.abs(w * (t[near] - t_zero - direction * tau)) <= tol
        reach = int(np.argmax(on)) if on.any() else near.size
        if reach < guard or attempt == 2:
            break
        guard = reach + 1
    return _Side(e, t_zero, float(np.mean(t[idx])), int(first + direction * min(reach, near.size - 1)))


def _release(engine, specimen: Specimen, amplitude: float, sign: float, dt: float, n_impacts: int, release: int):
    """Impact and flight points of one release from rest at sign * amplitude * alpha."""
    alpha, p, r_h = specimen.alpha, specimen.p, specimen.r_housner
    th0 = sign * amplitude * alpha
    # long enough for n_impacts + 1 of Housner's impacts, with a margin for an engine that loses less
    e0 = math.cos(alpha - abs(th0)) - math.cos(alpha)
    peaks = alpha - np.arccos(math.cos(alpha) + r_h ** np.arange(n_impacts + 2) * e0)
    duration = 0.5 * float(half_cycle_time(peaks[0], alpha, p)) + float(half_cycle_time(peaks[1:], alpha, p).sum())
    motion = GroundMotion.free_vibration(
        th0, 1.25 * duration + 20 * dt, dt=dt, name=f"release {th0 / alpha:+.4g} alpha"
    )
    resp = engine.simulate(specimen, motion)
    t, theta, w = np.asarray(resp.t, float), np.asarray(resp.theta, float), np.asarray(resp.theta_dot, float)
    J = np.concatenate(([0.0], np.cumsum(0.5 * (w[1:] ** 2 + w[:-1] ** 2) * np.diff(t))))
    cross = _crossings(theta, SWING_TOL * peaks[-1])[: n_impacts + 1]
    bounds = np.concatenate(([0], cross, [theta.size - 1]))
    sides = []
    for k, i_c in enumerate(cross[:n_impacts]):
        a, b = theta[i_c], theta[i_c + 1]
        t_c = float(t[i_c] + (t[i_c + 1] - t[i_c]) * a / (a - b))
        pre = _fit_side(t, theta, i_c, bounds[k], -1, dt, alpha, p)
        post = _fit_side(t, theta, i_c, bounds[k + 2], +1, dt, alpha, p)
        sides.append([pre, post, t_c])
    # The fits give each flight's energy over its window; the flight's own change between the windows, carried
    # linearly in time to the impacts, gives the energies at the impact instants.
    e_at = [[pre.e if pre else math.nan, post.e if post else math.nan] for pre, post, _ in sides]
    for k in range(len(sides) - 1):
        a_side, b_side = sides[k][1], sides[k + 1][0]
        if a_side is None or b_side is None or not b_side.t_window > a_side.t_window:
            continue
        rate = (b_side.e - a_side.e) / (b_side.t_window - a_side.t_window)
        e_at[k][1] = a_side.e - rate * (a_side.t_window - sides[k][2])
        e_at[k + 1][0] = b_side.e + rate * (sides[k + 1][2] - b_side.t_window)
    impacts = []
    for k, (pre, post, t_c) in enumerate(sides):
        e_pre, e_post = e_at[k]
        if pre is None or post is None or not (e_pre > 0 and e_post > 0):
            continue
        w_pre, w_post = math.sqrt(2.0 * e_pre), math.sqrt(2.0 * e_post)
        r = e_post / e_pre
        contact = (post.edge - pre.edge - 1) * dt
        impacts.append(
            (release, k + 1, t_c, w_pre, w_post, w_pre / (p * alpha), r, r / r_h, contact, post.t_zero - pre.t_zero)
        )
    flights = []
    for k in range(len(sides) - 1):
        post, pre = sides[k][1], sides[k + 1][0]
        if post is None or pre is None:
            continue
        e_start, e_end = e_at[k][1], e_at[k + 1][0]
        j0, j1 = np.interp([sides[k][2], sides[k + 1][2]], t, J)
        half = pre.t_zero - post.t_zero
        arg = math.cos(alpha) + 0.5 * (e_start + e_end) / (p * p)
        t_h = float(half_cycle_time(alpha - math.acos(arg), alpha, p)) if -1.0 < arg < 1.0 else math.nan
        flights.append(
            (
                release,
                k + 1,
                math.sqrt(2.0 * e_start) / (p * alpha),
                e_start,
                e_end,
                (e_end - e_start) / e_start,
                -(e_end - e_start) / (j1 - j0),
                half,
                t_h,
                half / t_h - 1.0,
            )
        )
    return impacts, flights


# ----------------------------------------------------------------------------
# binning


def _spread(v: np.ndarray) -> float:
    """IQR / 1.349 from 4 values on (a standard deviation for a normal sample), else the standard deviation."""
    if v.size >= 4:
        q1, q3 = np.percentile(v, [25, 75])
        return float((q3 - q1) / 1.349)
    return float(np.std(v, ddof=1)) if v.size >= 2 else math.nan


def _binned(x: np.ndarray, columns: Mapping[str, np.ndarray]) -> dict:
    """Per non-empty log bin of x (:data:`X_EDGES`): median x, n, and each column's median and spread."""
    out: dict = {"x": [], "n": [], "x_low": [], "x_high": []}
    for key in columns:
        out[f"{key}_median"], out[f"{key}_spread"] = [], []
    which = np.digitize(x, X_EDGES) - 1
    for b in range(X_EDGES.size - 1):
        m = (which == b) & np.isfinite(x)
        if not m.any():
            continue
        out["x"].append(float(np.median(x[m])))
        out["n"].append(int(m.sum()))
        out["x_low"].append(float(X_EDGES[b]))
        out["x_high"].append(float(X_EDGES[b + 1]))
        for key, col in columns.items():
            v = col[m][np.isfinite(col[m])]
            out[f"{key}_median"].append(float(np.median(v)) if v.size else math.nan)
            out[f"{key}_spread"].append(_spread(v))
    return out


#: The binned impact table's columns after the bins' own: its name -> (the impacts' column, the statistic of
#: :func:`_binned`).
_IMPACT_TABLE = {
    "ratio_median": ("ratio_to_housner", "median"),
    "ratio_spread": ("ratio_to_housner", "spread"),
    "contact_median_s": ("contact_s", "median"),
    "contact_delay_median_s": ("contact_delay_s", "median"),
}
#: The binned flight table's columns after the bins' own, as :data:`_IMPACT_TABLE` for the flights.
_FLIGHT_TABLE = {
    "c_median_per_s": ("c_per_s", "median"),
    "c_spread_per_s": ("c_per_s", "spread"),
    "energy_change_median": ("energy_change", "median"),
    "period_drift_median": ("period_drift", "median"),
}


def _binned_table(rows: dict, table: Mapping[str, tuple[str, str]]) -> dict:
    """The binned table of ``rows`` (columns -> values, ``x`` among them): the bins' x, edges and n, then each
    column of ``table`` (:data:`_IMPACT_TABLE`, :data:`_FLIGHT_TABLE`)."""
    sources = dict.fromkeys(col for col, _ in table.values())
    b = _binned(np.asarray(rows["x"], float), {col: np.asarray(rows[col], float) for col in sources})
    return {
        "x": b["x"],
        "x_low": b["x_low"],
        "x_high": b["x_high"],
        "n": b["n"],
        **{name: b[f"{col}_{stat}"] for name, (col, stat) in table.items()},
    }


def _tables(impacts: dict, flights: dict) -> tuple[dict, dict]:
    return _binned_table(impacts, _IMPACT_TABLE), _binned_table(flights, _FLIGHT_TABLE)


# ----------------------------------------------------------------------------
# the measurement


def _measured_points(engine, name: str, specimen: Specimen, amps: tuple, dt: float, n_impacts: int, progress):
    """Every release's impacts and flights (:func:`_release`), as columns (:data:`_IMPACT_COLUMNS`,
    :data:`_FLIGHT_COLUMNS`) -> values over all releases; release i at ``amps[i]`` alpha toward +x for even i,
    -x for odd, each reported to ``progress`` (if given) under the engine's registry ``name``."""
    imp_rows, fl_rows = [], []
    for i, a in enumerate(amps):
        sign = 1.0 if i % 2 == 0 else -1.0
        imps, fls = _release(engine, specimen, a, sign, dt, n_impacts, i)
        imp_rows += imps
        fl_rows += fls
        if progress is not None:
            rat = np.median([row[7] for row in imps]) if imps else math.nan
            progress(
                f"{name}: release {i + 1}/{len(amps)} at {sign * a:+.4g} alpha: {len(imps)} impacts, "
                f"median r/r_housner {rat:.4f}"
            )
    impacts = {c: [row[j] for row in imp_rows] for j, c in enumerate(_IMPACT_COLUMNS)}
    flights = {c: [row[j] for row in fl_rows] for j, c in enumerate(_FLIGHT_COLUMNS)}
    return impacts, flights


def measure_maps(
    engine: str,
    specimen: Specimen = SEED,
    amplitudes: Sequence[float] = AMPLITUDES,
    dt: float = DT,
    n_impacts: int = N_IMPACTS,
    settings: Mapping | None = None,
    progress: Callable[[str], None] | None = None,
) -> EngineMaps:
    """Measure an engine's impact and flight maps on free-rocking releases (``docs/explanation/engine-maps.md``).

    Parameters
    ----------
    engine : str
        Registry name (``analytic`` names ``housner``).
    specimen : Specimen
        The block; the seed specimen by default.
    amplitudes : sequence of float
        Release amplitudes theta0 / alpha [-], each in (0, 1); release i goes toward +x for even i, -x for odd.
    dt : float
        Sample interval [s]; 1 ms keeps every adapter's default step.
    n_impacts : int
        Impacts measured per release.
    settings : mapping, optional
        The engine's settings (its defaults otherwise).
    progress : callable, optional
        Called with a line per release.

    Returns
    -------
    EngineMaps

    Raises
    ------
    ValueError
        An unknown engine or setting, an amplitude out of (0, 1), a bad ``dt`` or ``n_impacts``.
    housner.errors.EngineUnavailable
        The engine's package is not installed.
    """
    name = engine_registry_name(engine)
    amps = tuple(float(a) for a in amplitudes)
    if not amps or not all(0.0 < a < 1.0 for a in amps):
        raise ValueError(f"`amplitudes` must be theta0/alpha values in (0, 1), got {amplitudes!r}")
    if not (math.isfinite(dt) and 0.0 < dt <= 0.01):
        raise ValueError(f"`dt` must lie in (0, 0.01] s, got {dt!r}")
    if not (isinstance(n_impacts, int) and n_impacts >= 2):
        raise ValueError(f"`n_impacts` must be an integer of at least 2, got {n_impacts!r}")
    eng = get_engine(name, **dict(settings or {}))
    wall0 = time.perf_counter()
    impacts, flights = _measured_points(eng, name, specimen, amps, dt, n_impacts, progress)
    imp_table, fl_table = _tables(impacts, flights)
    spec = engine_spec(name)
    return EngineMaps(
        engine=name,
        label=spec.label,
        settings=_plain(eng.settings()),
        version=eng.version(),
        specimen=SpecimenFacts.from_json(_plain(specimen.describe())),
        dt_s=float(dt),
        amplitudes=amps,
        r_housner=specimen.r_housner,
        impacts=imp_table,
        flights=fl_table,
        impact_points=_plain(impacts),
        flight_points=_plain(flights),
        wall_s=time.perf_counter() - wall0,
        method={
            "n_impacts": n_impacts,
            "guard_s": GUARD_S,
            "window_s": WINDOW_S,
            "depart_fraction": DEPART_FRACTION,
            "x_edges": X_EDGES.tolist(),
        },
    )
