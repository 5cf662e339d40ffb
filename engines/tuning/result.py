"""What the tuner found: :class:`TuningResult`, its tables and its summary for the terminal."""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
import pandas as pd

from housner._values import JsonValue, json_number
from housner.engines.tuning.checks import DECAY_RTOL, RTOL, SMALL_WORST_FACTOR

__all__ = ["DecayCheck", "PulseCheck", "RatioCheck", "TuningResult"]


def settings_text(settings: dict) -> str:
    """Settings as one line, ``key=value, ...`` (floats to 4 significant digits)."""

    def fmt(v):
        if isinstance(v, (list, tuple)):
            return "(" + ", ".join(fmt(x) for x in v) + ")"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    return ", ".join(f"{k}={fmt(v)}" for k, v in settings.items())


def _number(row: pd.Series, col: str) -> float:
    """A row's number in ``col``, NaN where its table has no such column (a file of an earlier version)."""
    return float(row[col]) if col in row.index else math.nan


class _TableRow:
    """A check that is one row of a table of :class:`TuningResult`, each field read from the column of its name."""

    @classmethod
    def from_row(cls, row: pd.Series):
        """The check of one row of the table (the one place the columns are read by name): a number NaN, a word
        "" where the table of an earlier version has no such column."""
        values = {}
        for f in fields(cls):
            if f.type == "str":
                values[f.name] = str(row[f.name]) if f.name in row.index else ""
            elif f.type == "int":
                values[f.name] = int(row[f.name])
            else:
                values[f.name] = _number(row, f.name)
        return cls(**values)


@dataclass(frozen=True)
class RatioCheck(_TableRow):
    """One release from rest of checks 1 and 2: a row of :attr:`TuningResult.table` or
    :attr:`TuningResult.small_table`.

    Attributes
    ----------
    dt : float
        The sample step [s] (NaN: a file older than the sample steps).
    amplitude : float
        The release amplitude theta0/alpha [-].
    r_engine, r_target : float
        The energy ratio of the first impact, the engine's and the target [-] (NaN where the file has none).
    rel_error : float
        r_engine / r_target - 1 [-].
    """

    dt: float
    amplitude: float
    r_engine: float
    r_target: float
    rel_error: float


@dataclass(frozen=True)
class DecayCheck(_TableRow):
    """One peak of check 3's free decay: a row of :attr:`TuningResult.decay_table`.

    Attributes
    ----------
    dt : float
        The sample step [s] (NaN: a file older than the sample steps).
    impacts : int
        Impacts before the peak.
    peak_engine, peak_analytic : float
        The peak after that many impacts / alpha, the engine's and the exact sequence's [-].
    rel_error : float
        peak_engine / peak_analytic - 1 [-].
    """

    dt: float
    impacts: int
    peak_engine: float
    peak_analytic: float
    rel_error: float


@dataclass(frozen=True)
class PulseCheck(_TableRow):
    """One one-sine pulse of check 4 at one sample step: a row of :attr:`TuningResult.pulse_table`.

    Attributes
    ----------
    dt : float
        The sample step [s] (NaN: a file older than the sample steps).
    pulse : str
        The pulse's name ("" where the file names none).
    peak_engine, peak_analytic : float
        The first peak / alpha, the engine's and the analytic model's [-] (NaN where the file has none).
    rel_error : float
        peak_engine / peak_analytic - 1 [-].
    theta_max_engine, theta_max_analytic : float
        theta_max / alpha, the engine's and the analytic model's [-] (NaN where the file has none).
    theta_max_rel_error : float
        theta_max_engine / theta_max_analytic - 1 [-].
    theta_max_rtol : float
        Its accepted relative error [-].
    """

    dt: float
    pulse: str
    peak_engine: float
    peak_analytic: float
    rel_error: float
    theta_max_engine: float
    theta_max_analytic: float
    theta_max_rel_error: float
    theta_max_rtol: float


@dataclass(frozen=True, eq=False)
class TuningResult(JsonValue):
    """What :func:`housner.engines.tuning.tune` found; the tune JSON (``housner tune ENGINE --json``) is
    :meth:`to_json`, read back by :meth:`from_json` (a file of an earlier version too).

    Attributes
    ----------
    engine : str
        Engine name.
    specimen : str
        Specimen name.
    target_r : float
        Target kinetic-energy ratio [-].
    settings : dict
        The chosen candidate's settings.
    table : pandas.DataFrame
        Check 1 for the chosen settings, one row per sample step and
        amplitude: ``dt`` (sample step [s]), ``amplitude`` (theta0/alpha [-]),
        ``r_engine``, ``r_target`` and ``rel_error`` (r_engine / r_target - 1 [-]).
    cost_per_sim_second : float
        CPU seconds per simulated second of the chosen settings [s/s].
    met : bool or None
        True if the chosen settings pass every check that was run (None: a file that does not say).
    candidates : pandas.DataFrame
        Every candidate tried: ``settings`` (text), ``worst_rel_error`` and
        ``mean_rel_error`` (signed) of r at 0.2-0.9 alpha,
        ``small_worst_rel_error`` and ``small_mean_rel_error`` at small
        amplitudes, ``pulse_rel_error`` (worst |engine / analytic - 1| of the
        pulses' first peaks and theta_max), ``decay_rel_error`` (worst of the
        decay peaks), ``score`` (the largest error over its tolerance: the
        candidate passes when it is at most 1), ``cost_per_sim_second``,
        ``wall_per_sim_second``, ``met``, ``error`` (engine failure, if any),
        ``impact_energy_factor`` (the impact law's factor; 1: the contact alone).
        Errors of checks not run are NaN.
    pulse_table : pandas.DataFrame
        Check 4 for the chosen settings: ``dt``, ``pulse`` (name),
        ``peak_engine`` and ``peak_analytic`` (first peak / alpha [-]),
        ``rel_error``, ``theta_max_engine`` and ``theta_max_analytic``
        (theta_max / alpha [-]), ``theta_max_rel_error`` and
        ``theta_max_rtol`` (its accepted error [-]); empty when not checked.
    small_table : pandas.DataFrame
        Check 2 for the chosen settings, columns as ``table``; empty when not checked.
    decay_table : pandas.DataFrame
        Check 3 for the chosen settings: ``dt``, ``impacts``, ``peak_engine`` and
        ``peak_analytic`` (peak / alpha after that many impacts [-]) and
        ``rel_error``; empty when not checked.
    rtol : float
        Accepted relative error [-] (checks 1, 2 and 4).
    date : str
        ISO date of the run.
    version : str
        Engine package version.
    """

    engine: str
    specimen: str
    target_r: float
    settings: dict
    table: pd.DataFrame
    cost_per_sim_second: float
    met: bool | None
    candidates: pd.DataFrame
    pulse_table: pd.DataFrame = field(default_factory=pd.DataFrame)
    small_table: pd.DataFrame = field(default_factory=pd.DataFrame)
    decay_table: pd.DataFrame = field(default_factory=pd.DataFrame)
    rtol: float = RTOL
    date: str = field(default_factory=lambda: datetime.date.today().isoformat())
    version: str = ""

    @property
    def worst_rel_error(self) -> float:
        """Largest |r_engine / r_target - 1| of the chosen settings at 0.2-0.9 alpha [-] (NaN without a table)."""
        if "rel_error" not in self.table or not len(self.table):
            return math.nan
        return float(np.max(np.abs(self.table["rel_error"])))

    @property
    def reached_r(self) -> tuple[float, float, float]:
        """The chosen settings' r at the amplitudes of check 1: (mean, lowest, highest) [-], over every sample step."""
        r = self.table["r_engine"].to_numpy(float) if "r_engine" in self.table else np.empty(0)
        r = r[np.isfinite(r)]
        if not r.size:
            return (math.nan, math.nan, math.nan)
        return (float(r.mean()), float(r.min()), float(r.max()))

    def to_json(self) -> dict:
        """The tune JSON (JSON-serialisable): the fields, the r reached and the worst error, the tables by column
        and the candidates by row."""
        return {
            "engine": self.engine,
            "specimen": self.specimen,
            "target_r": self.target_r,
            "reached_r": list(self.reached_r),
            "rtol": self.rtol,
            "settings": {k: list(v) if isinstance(v, tuple) else v for k, v in self.settings.items()},
            "met": None if self.met is None else bool(self.met),
            "worst_rel_error": self.worst_rel_error,
            "cost_per_sim_second": self.cost_per_sim_second,
            "table": self.table.to_dict(orient="list"),
            "small_table": self.small_table.to_dict(orient="list"),
            "decay_table": self.decay_table.to_dict(orient="list"),
            "pulse_table": self.pulse_table.to_dict(orient="list"),
            "candidates": self.candidates.to_dict(orient="records"),
            "date": self.date,
            "version": self.version,
        }

    def to_dict(self) -> dict:
        """Plain data (JSON-serialisable) for reports and caches: :meth:`to_json`."""
        return self.to_json()

    @classmethod
    def from_json(cls, data: Any) -> TuningResult:
        """The result of a tune JSON (``reached_r`` and ``worst_rel_error`` follow from the table: read, not kept).

        A file of an earlier version (or one written by hand) may lack keys: a missing number is NaN, a missing
        table empty, ``met`` None, a missing word ""; a table whose columns differ in length is unusable, empty.
        """
        if isinstance(data, TuningResult):
            return data
        d = data if isinstance(data, dict) else {}

        def table(key: str, records: bool = False) -> pd.DataFrame:
            t = d.get(key) or ([] if records else {})
            try:
                return pd.DataFrame(t)
            except (ValueError, TypeError):  # columns of different lengths, or not a table: unusable
                return pd.DataFrame()

        met = d.get("met")
        return cls(
            engine=str(d.get("engine", "")),
            specimen=str(d.get("specimen", "")),
            target_r=json_number(d.get("target_r")),
            settings=dict(d.get("settings") or {}),
            table=table("table"),
            cost_per_sim_second=json_number(d.get("cost_per_sim_second")),
            met=None if met is None else bool(met),
            candidates=table("candidates", records=True),
            pulse_table=table("pulse_table"),
            small_table=table("small_table"),
            decay_table=table("decay_table"),
            rtol=json_number(d.get("rtol")),
            date=str(d.get("date", "")),
            version=str(d.get("version", "")),
        )

    @property
    def contact_alone(self) -> tuple[float, str] | None:
        """The closest the engine's contact gets without the impact law: (mean r [-], settings text), or None.

        Taken from the candidates with ``impact_energy_factor`` 1 (the best score's mean r error at
        0.2-0.9 alpha); None when no such candidate was tried or none ran.
        """
        c = self.candidates
        if "impact_energy_factor" not in c or "mean_rel_error" not in c:
            return None
        own = c[(c["impact_energy_factor"] == 1.0) & np.isfinite(c["score"].astype(float))]
        if own.empty:
            return None
        row = own.loc[own["score"].astype(float).idxmin()]
        return self.target_r * (1.0 + float(row["mean_rel_error"])), str(row["settings"])

    def _law_line(self, law: float) -> str:
        """What the impact law does in the chosen settings, and how close the contact alone got."""
        line = (
            f"with the adapters' impact law: the block keeps {law:.4f} of the energy its contact leaves "
            f"it at each impact (housner.engines._impact_law.ImpactLaw); the contact itself loses Housner's share"
        )
        alone = self.contact_alone
        if alone is not None:
            line += (
                f". {self.engine}'s contact alone does not reach r = {self.target_r:.4f}: the closest of its "
                f"contact settings gets r = {alone[0]:.4f} on average ({alone[1]})"
            )
        return line

    def summary(self) -> str:
        """A few lines for the terminal: verdict, settings, errors of every check per sample step, cost."""
        verdict = "MET" if self.met else "NOT MET"
        n_ok = int(self.candidates["met"].sum())
        lines = [
            f"{self.engine} tuned to r = {self.target_r:.5g} for {self.specimen} "
            f"({self.date}, version {self.version}): "
            f"{verdict} (tolerance {self.rtol:.2%}; {n_ok} of {len(self.candidates)} candidates met it)",
            f"settings: {settings_text(self.settings)}",
        ]
        mean, lo, hi = self.reached_r
        amps = self.table["amplitude"].to_numpy(float)
        if not self.met and self.worst_rel_error > self.rtol:
            lines.insert(
                1,
                f"{self.engine} cannot reach r = {self.target_r:.4f} with the contact settings it offers; the closest "
                f"it gets: r = {mean:.4f} on average ({lo:.4f}-{hi:.4f} at {amps.min():g}-{amps.max():g} alpha), "
                f"{mean / self.target_r - 1:+.2%} from the target",
            )
        elif not self.met:
            lines.insert(
                1,
                f"{self.engine} reproduces r = {self.target_r:.4f} at {amps.min():g}-{amps.max():g} alpha (worst "
                f"{self.worst_rel_error:.2%}), but another check below is outside its tolerance",
            )
        law = float(self.settings.get("impact_energy_factor", 1.0))
        if law < 1.0:
            lines.insert(1, self._law_line(law))
        for dt, tab in self.table.groupby("dt", sort=False):
            lines.append(f"sample step {dt * 1e3:.4g} ms:")
            for label, t, tol in (
                ("r at 0.2-0.9 alpha", tab, f"{self.rtol:.2%}"),
                (
                    "r at small amplitudes",
                    self.small_table[self.small_table["dt"] == dt],
                    f"{SMALL_WORST_FACTOR * self.rtol:.2%}, mean {self.rtol:.2%}",
                ),
            ):
                if len(t):
                    k = int(np.argmax(np.abs(t["rel_error"].to_numpy())))
                    lines.append(
                        f"  {label} ({len(t)} amplitudes): worst {t['rel_error'].iloc[k]:+.3%} at "
                        f"{t['amplitude'].iloc[k]:g} alpha, mean {float(t['rel_error'].mean()):+.3%} (accepted {tol})"
                    )
            for row in self.decay_table[self.decay_table["dt"] == dt].itertuples():
                lines.append(
                    f"  free decay, peak after {row.impacts} impacts: {row.peak_engine:.5f} alpha vs analytic "
                    f"{row.peak_analytic:.5f} ({row.rel_error:+.3%}, accepted {DECAY_RTOL:.0%})"
                )
            for row in self.pulse_table[self.pulse_table["dt"] == dt].itertuples():
                lines.append(
                    f"  pulse {row.pulse}: first peak {row.peak_engine:.5f} alpha vs {row.peak_analytic:.5f} "
                    f"({row.rel_error:+.3%}); theta_max {row.theta_max_engine:.5f} vs {row.theta_max_analytic:.5f} "
                    f"({row.theta_max_rel_error:+.3%}, accepted {row.theta_max_rtol:.2%})"
                )
        lines.append(f"cost {self.cost_per_sim_second:.4g} CPU s per simulated s")
        return "\n".join(lines)


def result_tables(suites, e: dict, alpha: float, target: float, amps, small_amps, rtol: float) -> dict:
    """The chosen candidate's checks as tables, every sample step stacked: r, small r, decay, pulses."""
    meas = e["_meas"]
    chosen, small_t, decay_t, pulse_t = [], [], [], []
    for i, (suite, m) in enumerate(zip(suites, meas, strict=True)):
        n = len(amps)
        r = {"dt": suite.dt, "amplitude": amps, "r_engine": m["r"], "r_target": np.full(n, target)}
        chosen.append(pd.DataFrame(r).assign(rel_error=e["_rel"][i]))
        small_t.append(
            pd.DataFrame(
                {"dt": suite.dt, "amplitude": small_amps, "r_engine": m["small"], "r_target": target},
                index=range(len(small_amps)),
            ).assign(rel_error=e["_small"][i])
        )
        if suite.decay:
            decay = {"impacts": list(suite.decay_impacts), "peak_engine": m["decay"], "peak_analytic": suite.decay_ref}
            decay_t.append(pd.DataFrame({"dt": suite.dt, **decay, "rel_error": e["_decay"][i]}))
        pulse_t.append(
            pd.DataFrame(
                {
                    "dt": suite.dt,
                    "pulse": [x.name for x in suite.pulses],
                    "peak_engine": m["pulse"][:, 0] / alpha,
                    "peak_analytic": suite.pulse_ref[:, 0] / alpha,
                    "rel_error": e["_pulse"][i][:, 0],
                    "theta_max_engine": m["pulse"][:, 1] / alpha,
                    "theta_max_analytic": suite.pulse_ref[:, 1] / alpha,
                    "theta_max_rel_error": e["_pulse"][i][:, 1],
                    "theta_max_rtol": suite.pulse_tol[:, 1] * rtol,
                },
                index=range(len(suite.pulses)),
            )
        )
    decay_cols = ["dt", "impacts", "peak_engine", "peak_analytic", "rel_error"]
    return {
        "table": pd.concat(chosen, ignore_index=True),
        "small": pd.concat(small_t, ignore_index=True),
        "decay": pd.concat(decay_t, ignore_index=True) if decay_t else pd.DataFrame(columns=decay_cols),
        "pulse": pd.concat(pulse_t, ignore_index=True),
    }
