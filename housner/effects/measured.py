"""An engine's measured impact and flight maps, composed into Housner's kernel (effect ``measured_maps``).

An engine is characterised, record by record, by two maps measured on its free rocking
(:mod:`housner.scenarios.runs.impact_map`): the impact map k(x), the ratio by which its kinetic-energy
ratio at an impact differs from the ratio in force in Housner's model, and the flight map c(x) [1/s], the
rate of its loss of rocking energy between impacts as a viscous moment -c I0 theta', both against the
normalised speed x. :class:`MeasuredMaps` puts both into the analytic kernel as terms
(:mod:`housner.effects.terms`), the tables carried in the terms' parameters, so that "Housner + the engine's
measured maps" runs on the records the engine ran. It is a probe of the registry, built from a measurement
and never fitted. How the maps enter the kernel, and why its parameters are laid out so, are in
``docs/explanation/engine-maps.md`` ("The maps in Housner's kernel").
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from housner._kernel_parts import clip_unit
from housner._validate import vector
from housner.effects.registry import STAGE_DISSIPATION, Effect, param, register_effect
from housner.effects.terms import ImpactTerm, MomentTerm

__all__ = [
    "MeasuredMaps",
    "interp_log",
    "measured_flight_moment",
    "measured_impact_law",
    "measured_scatter_law",
    "scatter_q",
    "table_q",
]

#: Smallest capacity of a table in ``q`` (tables are padded to the next power of two, at least this).
MIN_CAPACITY = 8


# ----------------------------------------------------------------------
# the kernel's laws
@njit(cache=True, inline="always")
def _interp_column(x, q, cap, col):
    """Column ``col`` (1, 2, ...) of ``q = (n, x_1..x_cap, col 1, col 2, ...)`` at x: linear in log x, held at the
    end values beyond the table's ends."""
    n = int(q[0])
    base = 1 + col * cap
    if n == 1 or x <= q[1]:
        return q[base]
    if x >= q[n]:
        return q[base + n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if x >= q[1 + mid]:
            lo = mid
        else:
            hi = mid
    x0, x1 = q[1 + lo], q[1 + hi]
    y0, y1 = q[base + lo], q[base + hi]
    return y0 + (y1 - y0) * (math.log(x / x0) / math.log(x1 / x0))


@njit(cache=True, inline="always")
def interp_log(x, q):
    """The table of ``q = (n, x_1..x_N, y_1..y_N)`` at x: linear in log x, y_1 for x <= x_1, y_n for x >= x_n."""
    return _interp_column(x, q, (q.shape[0] - 1) // 2, 1)


@njit(cache=True)
def measured_impact_law(w, r, s, alpha, p2, q):
    """Energy ratio [-] of an impact at speed w > 0 [rad/s]: clip(r k(w / (p alpha)), 0, 1), k the table ``q``."""
    return clip_unit(r * interp_log(w / (math.sqrt(p2) * alpha), q))


@njit(cache=True, inline="always")
def _splitmix(z):
    """One step of SplitMix64 on an unsigned 64-bit integer (Steele, Lea & Flood 2014): a well-mixed hash."""
    z = z + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def measured_scatter_law(w, r, s, alpha, p2, q):
    """Energy ratio [-] of an impact at speed w: clip(r (k(x) + sigma(x) z), 0, 1), z a standard normal drawn
    from the impact's own speed and the seed: ``q = (n, x_1..x_N, k_1..k_N, sigma_1..sigma_N, seed)``.

    z is a pseudo-random number of the state, not of a stream: SplitMix64 of the bits of w and the seed, turned
    normal by Box-Muller. The same record and seed give the same impacts; another seed, another realisation.
    """
    cap = (q.shape[0] - 2) // 3
    x = w / (math.sqrt(p2) * alpha)
    k = _interp_column(x, q, cap, 1)
    sigma = _interp_column(x, q, cap, 2)
    bits = np.array([w]).view(np.uint64)[0]
    h1 = _splitmix(bits ^ _splitmix(np.uint64(int(q[q.shape[0] - 1]))))
    h2 = _splitmix(h1)
    u1 = (float(h1 >> np.uint64(11)) + 0.5) / 9007199254740992.0  # (0, 1): 53 bits
    u2 = float(h2 >> np.uint64(11)) / 9007199254740992.0
    z = math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)
    return clip_unit(r * (k + sigma * z))


@njit(cache=True, inline="always")
def measured_flight_moment(phi, w, t, a, v, s, alpha, p2, q):
    """Flight loss per unit I0 [rad/s^2], -c(x_E) w, c [1/s] the table ``q`` at the energy-equivalent speed x_E.

    x_E = sqrt(w^2 + 2 p^2 (cos(alpha - phi) - cos alpha)) / (p alpha) [-], phi = |theta| on the current pivot.
    """
    if q[0] == 1.0:  # a constant rate: no speed to compute
        return -(q[(q.shape[0] + 1) // 2] * w)
    e2 = w * w + 2.0 * p2 * (math.cos(alpha - phi) - math.cos(alpha))
    if e2 < 0.0:
        e2 = 0.0
    return -(interp_log(math.sqrt(e2) / (math.sqrt(p2) * alpha), q) * w)


def table_q(x: Sequence[float], y: Sequence[float]) -> tuple[float, ...]:
    """The parameters ``q = (n, x_1..x_N, y_1..y_N)`` of a table of n points, padded with 0 to its capacity N."""
    n = len(x)
    cap = max(MIN_CAPACITY, 1 << (n - 1).bit_length())
    pad = (0.0,) * (cap - n)
    return (float(n), *map(float, x), *pad, *map(float, y), *pad)


def scatter_q(x: Sequence[float], k: Sequence[float], sigma: Sequence[float], seed: int) -> tuple[float, ...]:
    """The parameters of :func:`measured_scatter_law`: ``(n, x_1..x_N, k_1..k_N, sigma_1..sigma_N, seed)``."""
    head = table_q(x, k)
    cap = (len(head) - 1) // 2
    return (*head, *map(float, sigma), *(0.0,) * (cap - len(sigma)), float(seed))


# ----------------------------------------------------------------------
# the tables
def _table(name_x: str, x, name_y: str, y, *, nonnegative: bool, allow_empty: bool) -> tuple[tuple, tuple]:
    """Validated (x, y) as tuples of floats; ValueError naming the argument."""
    arrays = []
    for name, v in ((name_x, x), (name_y, y)):
        a = vector(name, v, expected="a sequence of numbers", show=True)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"`{name}` must be finite, got {a.tolist()!r}")
        arrays.append(a)
    xa, ya = arrays
    if xa.size != ya.size:
        raise ValueError(f"`{name_x}` and `{name_y}` must have the same length, got {xa.size} and {ya.size}")
    if xa.size == 0 and not allow_empty:
        raise ValueError(f"`{name_x}` must hold at least one point")
    if np.any(xa <= 0.0):
        raise ValueError(f"`{name_x}` must be positive (speeds x = theta'/(p alpha) [-]), got {xa.tolist()!r}")
    if np.any(np.diff(xa) <= 0.0):
        raise ValueError(f"`{name_x}` must be strictly increasing, got {xa.tolist()!r}")
    if nonnegative and np.any(ya < 0.0):
        raise ValueError(f"`{name_y}` must be non-negative, got {ya.tolist()!r}")
    return tuple(float(v) for v in xa), tuple(float(v) for v in ya)


def _digest(*tables: tuple) -> float:
    """A fingerprint of the tables in [1, 2^52): the first 52 bits of a SHA-256 of their lengths and values."""
    h = hashlib.sha256()
    for t in tables:
        h.update(len(t).to_bytes(8, "little"))
        h.update(np.asarray(t, dtype="<f8").tobytes())
    return float(max(1, int(h.hexdigest()[:13], 16)))


@register_effect
@dataclass(frozen=True, init=False, repr=False)
class MeasuredMaps(Effect):
    """An engine's measured impact and flight maps in Housner's kernel (``docs/explanation/engine-maps.md``).

    Parameters
    ----------
    impact_x : sequence of float
        Pre-impact speeds x_i = theta'_before / (p alpha) [-], positive, strictly increasing (n >= 1).
    impact_ratio : sequence of float
        The factor k_i >= 0 [-] on the energy ratio in force at speed x_i: r' = clip(r k, 0, 1).
    flight_x : sequence of float, optional
        Energy-equivalent speeds x_j [-], positive, strictly increasing; empty (default): no flight term.
    flight_c : sequence of float, optional
        Flight loss rates c_j [1/s] at x_j: the moment -c I0 theta' (c > 0 a loss, c < 0 a gain).
    impact_spread : sequence of float, optional
        The standard deviation sigma_i >= 0 [-] of the factor at x_i, impact to impact; empty (default): every
        impact takes the mean k(x). Given, each impact takes k(x) + sigma(x) z, z a standard normal drawn from
        the impact's speed and ``seed`` (:func:`measured_scatter_law`): one realisation of an engine whose
        impacts scatter as measured.
    seed : int, optional
        The realisation of the scatter (0 by default; read only with ``impact_spread``).
    digest : float, optional
        The tables' fingerprint; read off them (give it only to check it). Without tables, 0: the neutral
        effect, which adds nothing.

    Notes
    -----
    Both tables are interpolated linearly in log x and held at their end values beyond their ends.
    Realised by the analytic engine through its terms (an :class:`~housner.effects.terms.ImpactTerm`,
    and a :class:`~housner.effects.terms.MomentTerm` zero at rest when a flight table is given).

    Examples
    --------
    >>> maps = MeasuredMaps.from_tables([0.1, 0.3, 1.0], [1.02, 0.99, 0.97], flight_x=[0.1, 1.0], flight_c=[0.2, 0.1])
    >>> resp = HousnerEngine().simulate(specimen, motion, [maps])  # doctest: +SKIP
    """

    name = "measured_maps"
    stage = STAGE_DISSIPATION
    probe = True  # built from a measurement: never a search candidate
    digest: float = param(
        "-", (0.0, 2.0**52), neutral=0.0, default=0.0, doc="fingerprint of the measured tables (read off them)"
    )

    def __init__(
        self,
        impact_x: Sequence[float] = (),
        impact_ratio: Sequence[float] = (),
        flight_x: Sequence[float] = (),
        flight_c: Sequence[float] = (),
        impact_spread: Sequence[float] = (),
        seed: int = 0,
        digest: float | None = None,
    ) -> None:
        empty = all(len(np.atleast_1d(v)) == 0 for v in (impact_x, impact_ratio, flight_x, flight_c, impact_spread))
        if empty:
            ix, ir, fx, fc, sp = (), (), (), (), ()
        else:
            ix, ir = _table("impact_x", impact_x, "impact_ratio", impact_ratio, nonnegative=True, allow_empty=False)
            fx, fc = _table("flight_x", flight_x, "flight_c", flight_c, nonnegative=False, allow_empty=True)
            sp = ()
            if len(np.atleast_1d(impact_spread)):
                _x, sp = _table(
                    "impact_x", impact_x, "impact_spread", impact_spread, nonnegative=True, allow_empty=False
                )
        if not (isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and 0 <= seed < 2**53):
            raise ValueError(f"`seed` must be an integer in [0, 2^53), got {seed!r}")
        seed = int(seed) if sp else 0
        own = 0.0 if empty else _digest(ix, ir, fx, fc, *((sp, (float(seed),)) if sp else ()))
        if digest is not None and digest != own:
            raise ValueError(
                f"`digest` of effect 'measured_maps' is read off its tables ({own!r}), got {digest!r}: "
                "build the effect with MeasuredMaps.from_tables(impact_x, impact_ratio, flight_x, flight_c)"
            )
        for key, value in (
            ("impact_x", ix),
            ("impact_ratio", ir),
            ("flight_x", fx),
            ("flight_c", fc),
            ("impact_spread", sp),
            ("seed", seed),
        ):
            object.__setattr__(self, key, value)
        object.__setattr__(self, "digest", own)
        self.__post_init__()

    @classmethod
    def from_tables(
        cls,
        impact_x: Sequence[float],
        impact_ratio: Sequence[float],
        flight_x: Sequence[float] = (),
        flight_c: Sequence[float] = (),
    ) -> MeasuredMaps:
        """The effect of an impact table (x_i, k_i) and an optional flight table (x_j, c_j [1/s])."""
        if len(np.atleast_1d(impact_x)) == 0:
            raise ValueError("`impact_x` must hold at least one point")
        return cls(impact_x, impact_ratio, flight_x, flight_c)

    @classmethod
    def from_engine_maps(cls, maps) -> MeasuredMaps:
        """The effect of an engine's measured maps: any object with ``impact_table()`` and ``flight_table()``
        returning (x, y) arrays (``housner.scenarios.runs.impact_map.EngineMaps``); bins whose x or y is not
        finite (no data) are left out."""
        tables = []
        for name in ("impact_table", "flight_table"):
            if not callable(getattr(maps, name, None)):
                raise ValueError(f"`maps` must have an {name}() method (an EngineMaps), got {type(maps).__name__}")
            x, y = (np.asarray(v, dtype=np.float64).ravel() for v in getattr(maps, name)())
            ok = np.isfinite(x) & np.isfinite(y) if x.shape == y.shape else slice(None)
            tables += [x[ok], y[ok]]
        return cls.from_tables(*tables)

    def __repr__(self) -> str:
        return (
            f"MeasuredMaps(impact: {len(self.impact_x)} points, flight: {len(self.flight_x)} points, "
            + (f"scatter seed {self.seed}, " if self.impact_spread else "")
            + f"digest={self.digest:.0f})"
        )

    def describe(self) -> dict:
        """Plain data: the name, the fingerprint and the tables."""
        return {
            "name": self.name,
            "digest": self.digest,
            "impact_x": list(self.impact_x),
            "impact_ratio": list(self.impact_ratio),
            "flight_x": list(self.flight_x),
            "flight_c": list(self.flight_c),
            **({"impact_spread": list(self.impact_spread), "seed": self.seed} if self.impact_spread else {}),
        }

    def terms(self, params, specimen) -> tuple:
        """The impact term (and the flight term when a flight table is given); none for the neutral effect."""
        out = []
        if self.impact_spread:
            q = scatter_q(self.impact_x, self.impact_ratio, self.impact_spread, self.seed)
            out.append(ImpactTerm(measured_scatter_law, q))
        elif self.impact_x:
            out.append(ImpactTerm(measured_impact_law, table_q(self.impact_x, self.impact_ratio)))
        if self.flight_x:
            out.append(MomentTerm(measured_flight_moment, table_q(self.flight_x, self.flight_c), at_rest=False))
        return tuple(out)
