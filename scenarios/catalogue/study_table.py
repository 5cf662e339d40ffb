"""The ``[study]`` table of a scenario: stripes of intensity, specimen sizes, thresholds (declarative).

:func:`read_study` checks the table and builds the :class:`Study`; running it is
:func:`housner.scenarios.studies.run_study`'s work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from housner.errors import unknown_choice

__all__ = ["INTENSITIES", "Study", "read_study"]

#: Intensity measures of a study's stripes: name -> label (dimensionless).
INTENSITIES = {
    "amplitude": "amplitude factor on the ensemble [-]",
    "pga": "PGA / (g tan alpha) [-]",
    "pgv": "PGV p / (g tan alpha) [-]",
    "sa": "Sa(T, 5 %) / (g tan alpha) [-]",
}

#: Motion sources a study can scale (ground motions; not free vibration or pulse grids).
_SOURCES = ("rdk", "record", "records")


@dataclass(frozen=True)
class Study:
    """The ``[study]`` table of a scenario.

    Attributes
    ----------
    intensity : str
        A key of :data:`INTENSITIES`.
    levels : tuple of float
        The stripes: amplitude factors [-] or target values of the intensity measure [-], increasing.
    S : tuple of float
        Size ratios prototype / model [-], one per size, increasing.
    prototype_heights : tuple of float
        The same sizes as prototype heights [m] (S times the model's height).
    thresholds : tuple of float
        theta_max / alpha levels of the exceedance curves [-].
    period : float or None
        T [s] at prototype scale of ``intensity = "sa"``.
    n_boot : int
        Bootstrap resamples of the motions.
    seed : int
        Seed of the bootstrap.
    histories : bool
        Keep the records' theta histories in memory (off: memory stays flat).
    ci : float
        Confidence level of every interval.
    """

    intensity: str
    levels: tuple[float, ...]
    S: tuple[float, ...]
    prototype_heights: tuple[float, ...]
    thresholds: tuple[float, ...] = (0.5, 0.8, 1.0)
    period: float | None = None
    n_boot: int = 1000
    seed: int = 0
    histories: bool = False
    ci: float = 0.95

    @property
    def label(self) -> str:
        """The intensity measure's axis label."""
        label = INTENSITIES[self.intensity]
        return label.replace("T,", f"T = {self.period:g} s,") if self.intensity == "sa" else label

    def describe(self) -> dict:
        """Plain data for study.json."""
        return {
            "intensity": self.intensity,
            "intensity_label": self.label,
            "levels": list(self.levels),
            "S": list(self.S),
            "prototype_heights": list(self.prototype_heights),
            "thresholds": list(self.thresholds),
            "period": self.period,
            "n_boot": self.n_boot,
            "seed": self.seed,
            "histories": self.histories,
            "ci": self.ci,
        }


def _positive_list(f, key: str, value: Any, *, increasing: bool = True) -> tuple[float, ...]:
    """A non-empty list of positive finite numbers (sorted, distinct when ``increasing``), or a ScenarioError."""
    ok = (
        isinstance(value, list)
        and value
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in value)
    )
    if not ok:
        raise f.error("study", key, f"[study] {key!r} must be a non-empty list of positive numbers, got {value!r}")
    out = tuple(float(v) for v in value)
    if increasing and any(b <= a for a, b in zip(out, out[1:], strict=False)):
        raise f.error("study", key, f"[study] {key!r} must increase (each value once), got {value!r}")
    return out


def read_study(f, table: dict, motions: dict, specimen, S0: float) -> Study:
    """Check a scenario's ``[study]`` table (types already checked by the schema) and build the :class:`Study`.

    Parameters
    ----------
    f : housner.scenarios.catalogue.schema.ScenarioFile
        The scenario file (messages name it, the key and its line).
    table : dict
        The ``[study]`` table.
    motions : dict
        The ``[motions]`` table (the source must be ground motions).
    specimen : Specimen
        The model (its height turns S into prototype heights).
    S0 : float
        The scenario's own size ratio [-] (the default size).
    """
    src = motions.get("source")
    if src not in _SOURCES:
        raise f.error(
            "motions",
            "source",
            f"a [study] scales ground motions: [motions] source must be one of {', '.join(_SOURCES)}, got {src!r}",
        )
    intensity = table.get("intensity", "amplitude")
    if intensity not in INTENSITIES:
        raise f.error("study", "intensity", f"[study] {unknown_choice('intensity', intensity, INTENSITIES)}")
    if "levels" not in table:
        raise f.error("study", None, "[study] needs `levels` (the stripes: amplitude factors or intensity values)")
    levels = _positive_list(f, "levels", table["levels"])
    period = table.get("period")
    if intensity == "sa":
        if period is None or not period > 0:
            msg = f'[study] intensity "sa" needs `period` > 0 [s, prototype scale], got {period!r}'
            raise f.error("study", "period" if period is not None else None, msg)
        period = float(period)
    elif period is not None:
        raise f.error("study", "period", f'[study] `period` belongs to intensity "sa", not {intensity!r}')
    if "prototype_heights" in table and "S" in table:
        raise f.error("study", "S", "[study] give the sizes as `prototype_heights` or as `S`, not both")
    if "prototype_heights" in table:
        heights = _positive_list(f, "prototype_heights", table["prototype_heights"])
        sizes = tuple(h / specimen.height for h in heights)
    elif "S" in table:
        sizes = _positive_list(f, "S", table["S"])
    else:
        sizes = (float(S0),)
    thresholds = _positive_list(f, "thresholds", table.get("thresholds", [0.5, 0.8, 1.0]))
    n_boot = table.get("bootstrap", 1000)
    if not 100 <= n_boot <= 100_000:
        raise f.error("study", "bootstrap", f"[study] `bootstrap` must lie in [100, 100000], got {n_boot!r}")
    seed = table.get("seed", 0)
    if seed < 0:
        raise f.error("study", "seed", f"[study] `seed` must be a non-negative integer, got {seed!r}")
    return Study(
        intensity=intensity,
        levels=levels,
        S=sizes,
        prototype_heights=tuple(s * specimen.height for s in sizes),
        thresholds=thresholds,
        period=period,
        n_boot=int(n_boot),
        seed=int(seed),
        histories=bool(table.get("histories", False)),
    )
