"""The contact-tuning figure: an engine's energy ratio against release amplitude, with the target."""

from __future__ import annotations

import pandas as pd

from housner.engines.tuning import SMALL_WORST_FACTOR

__all__ = ["tuning_report_figure"]


def tuning_report_figure(result):
    """Energy ratio against release amplitude for the chosen settings, with the target and its bands.

    Parameters
    ----------
    result : TuningResult

    Returns
    -------
    matplotlib.figure.Figure
        r_engine [-] against theta0/alpha [-], one line per sample step
        (small amplitudes included), the target r as a line, the +-rtol band
        shaded and the +-3 rtol band of single small-amplitude impacts dotted.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 4.0), layout="constrained")
    ax = fig.add_subplot()
    r0, tol = result.target_r, result.rtol
    ax.axhspan(r0 * (1 - tol), r0 * (1 + tol), color="tab:green", alpha=0.15, label=f"target +- {tol:.1%}")
    ax.axhline(r0, color="tab:green", lw=1.5, label=f"target r = {r0:.4f}")
    if len(result.small_table):
        wide = SMALL_WORST_FACTOR * tol
        for y in (r0 * (1 - wide), r0 * (1 + wide)):
            ax.axhline(y, color="tab:green", lw=0.8, ls=":")
    both = pd.concat([result.small_table, result.table], ignore_index=True).sort_values(["dt", "amplitude"])
    for dt, t in both.groupby("dt", sort=False):
        ax.plot(t["amplitude"], t["r_engine"], ".-", lw=0.8, label=f"{result.engine}, samples every {dt * 1e3:.3g} ms")
    ax.set_xlabel(r"release amplitude $\theta_0/\alpha$ [-]")
    ax.set_ylabel("energy ratio at first impact r [-]")
    verdict = "met" if result.met else "NOT met"
    ax.set_title(f"{result.engine} contact tuning: target {verdict}, worst error {result.worst_rel_error:.2%}")
    ax.legend(loc="best", fontsize="small")
    return fig
