"""The figures of the outcome report: measured outcomes over PGA and PGV/PGA with the P = 0.5 fragility lines,
and the calibration curve.

A model of outcomes gives a probability per record, not a line: the line drawn is the 0.5 level of a smooth
surface fitted to those probabilities (:func:`fit_soft_logistic`, a logistic regression on the logarithms of
PGA and PGV/PGA, with quadratic terms for a model and linear ones for a baseline, fitted to the probabilities
as soft targets). It summarises where the records' P crosses 1/2; it is not the model evaluated off the records.

Coordinates are the figure's: PGA [g] and PGV/PGA [s], both on log axes (the surface is fitted in their
natural logarithms, so the unit of PGA only shifts its intercept).

References
----------
Purvance, M. D., Abdolrasool, A., Brune, J. N. (2008). Freestanding block overturning fragilities: numerical
simulation and experimental validation. EESD 37(5), 791-808 (fragilities over PGA and PGV/PGA).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure
from scipy import optimize, special

from housner.units import G

__all__ = [
    "GRID",
    "SoftLogistic",
    "baseline_label",
    "calibration_figure",
    "fit_soft_logistic",
    "level_lines",
    "outcome_map_figure",
    "plot_limits",
]

#: Points per axis of the grid the P = 0.5 line is traced on [-] (log-spaced over the plotted range).
GRID = 160
#: Ridge penalty of the surface's coefficients (on standardised logs) [-]: keeps a fit to outcomes that a line
#: separates finite, while the boundary stays in the gap between the two classes.
RIDGE = 1e-3
#: Share of the data's log range added on each side of the plot [-].
PAD = 0.08

_OVERTURNED = "#c0392b"
_STOOD = "#1f77b4"
_PLAIN = "#7f7f7f"
_FINAL = "#0b5394"
_BASELINE = "#e67e22"


@dataclass(frozen=True)
class SoftLogistic:
    """P = expit(coef . features) over (PGA [g], PGV/PGA [s]): features 1, a, b (and a^2, a b, b^2 when
    ``quadratic``), with a, b the standardised natural logs.

    Attributes
    ----------
    coef : ndarray
    mean, scale : ndarray
        Mean and standard deviation of (ln PGA, ln PGV/PGA) of the records it was fitted to.
    quadratic : bool
    """

    coef: np.ndarray
    mean: np.ndarray
    scale: np.ndarray
    quadratic: bool

    def features(self, pga_g, ratio_s) -> np.ndarray:
        """Design matrix of the points (PGA [g], PGV/PGA [s]): one row per point."""
        a = (np.log(np.asarray(pga_g, float)).ravel() - self.mean[0]) / self.scale[0]
        b = (np.log(np.asarray(ratio_s, float)).ravel() - self.mean[1]) / self.scale[1]
        cols = [np.ones_like(a), a, b] + ([a * a, a * b, b * b] if self.quadratic else [])
        return np.column_stack(cols)

    def __call__(self, pga_g, ratio_s) -> np.ndarray:
        """P at the points (PGA [g], PGV/PGA [s]) [-], shaped like ``pga_g``."""
        shape = np.shape(pga_g)
        return special.expit(self.features(pga_g, ratio_s) @ self.coef).reshape(shape)


def fit_soft_logistic(pga_g, ratio_s, p, *, quadratic: bool = True, ridge: float = RIDGE) -> SoftLogistic:
    """The logistic surface closest to the probabilities ``p`` in cross-entropy.

    Parameters
    ----------
    pga_g, ratio_s : array_like
        PGA [g] and PGV/PGA [s] of the records (positive).
    p : array_like
        Each record's probability [-] (a model's out-of-fold P, or 0/1 outcomes): the soft targets.
    quadratic : bool
        Quadratic terms in the logs (a curved 0.5 line); False fits a plane in the logs (a straight line).
    ridge : float
        Penalty on the squared coefficients other than the intercept [-].

    Returns
    -------
    SoftLogistic
    """
    x, y = np.asarray(pga_g, float).ravel(), np.asarray(ratio_s, float).ravel()
    t = np.clip(np.asarray(p, float).ravel(), 0.0, 1.0)
    if x.size != t.size or y.size != t.size or not (np.all(x > 0) and np.all(y > 0)):
        raise ValueError("`pga_g` and `ratio_s` must be positive and as long as `p`")
    u = np.column_stack((np.log(x), np.log(y)))
    mean, scale = u.mean(axis=0), u.std(axis=0)
    scale[scale == 0] = 1.0
    shell = SoftLogistic(np.zeros(6 if quadratic else 3), mean, scale, quadratic)
    Z = shell.features(x, y)
    penal = np.ones(Z.shape[1])
    penal[0] = 0.0

    def loss(c):
        z = Z @ c
        val = float(np.sum(np.logaddexp(0.0, z) - t * z) + ridge * np.sum(penal * c * c))
        grad = Z.T @ (special.expit(z) - t) + 2.0 * ridge * penal * c
        return val, grad

    c = optimize.minimize(loss, np.zeros(Z.shape[1]), jac=True, method="L-BFGS-B", options={"maxiter": 2000}).x
    return SoftLogistic(c, mean, scale, quadratic)


def plot_limits(values) -> tuple[float, float]:
    """The plotted range of positive ``values``: their range padded by :data:`PAD` of it on each side, in logs."""
    lo, hi = np.log(np.min(values)), np.log(np.max(values))
    pad = PAD * max(hi - lo, 0.2)
    return float(np.exp(lo - pad)), float(np.exp(hi + pad))


def level_lines(surface: SoftLogistic, pga_lim, ratio_lim, *, n: int = GRID, level: float = 0.5) -> list:
    """The ``level`` line of ``surface`` over the plotted range.

    Traced on an ``n`` x ``n`` grid, log-spaced in PGA [g] within ``pga_lim`` and PGV/PGA [s] within
    ``ratio_lim``, by linear interpolation between grid nodes (matplotlib's contouring).

    Returns
    -------
    list of ndarray
        Segments, each (k, 2) of (PGA [g], PGV/PGA [s]); empty when P does not cross ``level`` in the range.
    """
    X, Y = np.meshgrid(np.geomspace(*pga_lim, n), np.geomspace(*ratio_lim, n))
    P = surface(X, Y)
    if not (P.min() < level < P.max()):
        return []
    cs = Figure().add_subplot().contour(X, Y, P, levels=[level])
    return [s for s in cs.allsegs[0] if len(s) > 1]


def outcome_map_figure(diag, best: str) -> Figure:
    """Measured outcomes over PGA [g] and PGV/PGA [s], with the 0.5 lines of the plain and the final model
    (quadratic surfaces of their out-of-fold P) and of the baseline ``best`` (a plane in the logs, dashed);
    the final model's misses circled. Each line's legend says on how many records its side of the line agrees
    with the side of 0.5 that the record's own P is on (how faithful the smooth summary is)."""
    x = np.asarray(diag.pga, float) / G
    y = np.asarray(diag.pgv, float) / np.asarray(diag.pga, float)
    obs = np.asarray(diag.observed, bool)
    xl, yl = plot_limits(x), plot_limits(y)
    fig = Figure(figsize=(7.8, 6.4))
    ax = fig.add_subplot()
    same = len(diag.steps) == 1
    lines = [(diag.steps[0].p, True, _PLAIN, "-", 1.4, "plain model" + (" (= final)" if same else ""))]
    if not same:
        lines.append((diag.final.p, True, _FINAL, "-", 2.4, f"final model: plain + {_plus(diag.final.name)}"))
    lines.append((diag.baseline_p[best], False, _BASELINE, "--", 1.6, f"best baseline: {baseline_label(best)}"))
    for p, quad, color, ls, lw, label in lines:
        surface = fit_soft_logistic(x, y, p, quadratic=quad)
        segs = level_lines(surface, xl, yl)
        for s in segs:
            ax.plot(s[:, 0], s[:, 1], color=color, ls=ls, lw=lw, zorder=2)
        agree = int(np.sum((surface(x, y) >= 0.5) == (np.asarray(p) >= 0.5)))
        where = f"line agrees with {agree}/{x.size} records' P" if segs else "no 0.5 line in the range"
        ax.plot([], [], color=color, ls=ls, lw=lw, label=f"P = 0.5: {label} ({where})")
    ax.plot(x[obs], y[obs], "^", color=_OVERTURNED, ms=6, label=f"overturned ({int(obs.sum())})", zorder=4)
    ax.plot(
        x[~obs], y[~obs], "o", mfc="none", mec=_STOOD, mew=1.3, ms=6, label=f"stood ({int((~obs).sum())})", zorder=4
    )
    miss = (np.asarray(diag.final.p) >= 0.5) != obs
    ax.plot(
        x[miss],
        y[miss],
        "o",
        mfc="none",
        mec="#000000",
        mew=1.2,
        ms=13,
        zorder=5,
        label=f"missed by the final model ({int(miss.sum())})",
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(*xl)
    ax.set_ylim(*yl)
    ax.set_xlabel("PGA [g]")
    ax.set_ylabel("PGV/PGA [s]")
    ax.set_title("Measured outcomes and the models' P = 0.5 lines", fontsize=11)
    ax.grid(True, alpha=0.3, which="both")
    # below the axes: inside, the legend would hide records
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.11), ncol=2, frameon=False)
    fig.tight_layout()
    return fig


def calibration_figure(final_rows: list, baseline_rows: list, final_label: str, baseline_label_: str) -> Figure:
    """Observed share of overturns against the mean P of each bin, with 95 % Wilson intervals, for the final
    model and a baseline (rows of :func:`housner.scenarios.diagnosis.outcomes.outcome_scores.calibration_table`)."""
    fig = Figure(figsize=(6.4, 5.0))
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1], color="#555555", lw=1, ls=":", label="calibrated (observed = P)")
    for rows, color, marker, label, dx in (
        (final_rows, _FINAL, "o", final_label, -0.006),
        (baseline_rows, _BASELINE, "s", baseline_label_, 0.006),
    ):
        if not rows:
            continue
        mp = np.array([r.mean_p for r in rows])
        ob = np.array([r.observed for r in rows])
        lo = np.array([r.observed_ci[0] for r in rows])
        hi = np.array([r.observed_ci[1] for r in rows])
        ax.errorbar(
            mp + dx, ob, yerr=[ob - lo, hi - ob], fmt=marker + "-", color=color, capsize=3, lw=1.3, ms=6, label=label
        )
        for r, xx in zip(rows, mp + dx, strict=True):
            ax.annotate(
                f"n={r.n}",
                (xx, r.observed),
                textcoords="offset points",
                xytext=(6, -11 if dx < 0 else 5),
                fontsize=7,
                color=color,
                bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 0.6},
            )
    ax.set_xlim(-0.04, 1.1)  # room for the counts beside the end bins
    ax.set_ylim(-0.04, 1.06)
    ax.set_xlabel("mean predicted P(overturn) of the bin [-]")
    ax.set_ylabel("observed share overturned [-]")
    ax.set_title("Calibration (out-of-fold P, bins of 0.2)", fontsize=11)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7.5, loc="lower right")  # below the diagonal's far end: where no bin of a useful model lies
    fig.tight_layout()
    return fig


def engine_azimuth_figure(azimuth, overturns, measured: int, chosen, engine: str) -> Figure:
    """Runs that overturn at each azimuth of a 3D engine's ensemble (``overturns``, the mean over its members at
    that azimuth [count]) against the tests that did (``measured``), the azimuths the orientation fit chose
    (``chosen`` [deg]) marked."""
    fig = Figure(figsize=(6.4, 3.6))
    ax = fig.add_subplot()
    az = np.asarray(azimuth, dtype=float)
    width = 0.8 * (360.0 / max(az.size, 1))
    colors = [_FINAL if a in set(chosen) else "#9aa7b5" for a in az]
    ax.bar(az, overturns, width=width, color=colors, label=f"{engine} runs that overturn (fitted orientation dark)")
    ax.axhline(measured, color=_BASELINE, lw=1.5, ls="--", label=f"tests that overturned ({measured})")
    ax.set_xticks(az)
    ax.set_xlabel("azimuth: shaking direction from the mesh x axis [deg]")
    ax.set_ylabel("records that overturn [count]")
    ax.set_title("The rock's unrecorded orientation decides the 3D outcome", fontsize=11)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper right")
    fig.tight_layout()
    return fig


def baseline_label(name: str) -> str:
    """A baseline's name in words: ``logistic_pga_pgv`` -> "logistic on log PGA and log PGV"."""
    if name == "base_rate":
        return "base rate (the share of overturns in the training folds)"
    if not name.startswith("logistic_"):
        return name
    feats = [f"log {f.upper()}" for f in name[len("logistic_") :].split("_")]
    return "logistic on " + " and ".join(feats)


def _plus(name: str) -> str:
    return " + ".join(name.split("+"))
