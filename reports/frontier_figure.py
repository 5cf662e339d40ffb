"""The accuracy-cost frontier figure of an engine (:mod:`housner.scenarios.runs.frontier`)."""

from __future__ import annotations

import math

import numpy as np

from housner.engines.tuning import DECAY_RTOL, RTOL
from housner.scenarios.runs.frontier import Frontier
from housner.statistics.proportions import wilson_interval

__all__ = ["frontier_figure"]

_MARKERS = ("o", "s", "^", "D")


def _value_label(axis: str, settings: dict) -> str:
    if not axis:
        return "defaults"
    v = settings[axis]
    if axis == "timestep":
        return f"{v * 1e3:g} ms"
    if isinstance(v, (list, tuple)):
        v = v[0]
    return f"{axis} {v:g}" if isinstance(v, float) else f"{axis} {v}"


def frontier_figure(frontier: Frontier):
    """Accuracy against cost at each point of an engine's sweep, the defaults and the knee marked.

    Parameters
    ----------
    frontier : Frontier

    Returns
    -------
    matplotlib.figure.Figure
        Left: per-record agreement with the analytic model [-] (95 % Wilson intervals) against CPU
        seconds per simulated second [s/s] (log), the model-form floor dashed. Right: the worst
        error of r at 0.2-0.9 alpha and of the 40-impact free decay [%] against the same cost,
        their tolerances dotted. Markers: one shape per swept setting; a ring marks the defaults,
        a star the knee.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 4.0), layout="constrained")
    ax_a, ax_e = fig.subplots(1, 2)
    axes = [""] + list(frontier.axes)
    pts = [p for p in frontier.points if not p.error and math.isfinite(p.cpu_per_sim_second)]
    for k, axis in enumerate(axes):
        group = [p for p in pts if p.axis == axis]
        if not group:
            continue
        x = np.array([p.cpu_per_sim_second for p in group])
        y = np.array([p.agreement for p in group])
        lo, hi = wilson_interval(np.round(y * np.array([p.n_records for p in group])), [p.n_records for p in group])
        mk = _MARKERS[k % len(_MARKERS)]
        label = None if not axis else f"{axis} swept"  # the defaults: the ring
        ax_a.errorbar(x, y, yerr=[y - lo, hi - y], fmt=mk, ms=6, capsize=2, label=label)
        ax_e.plot(x, [abs(p.r_error) * 100 for p in group], mk, color="tab:blue", ms=6)
        ax_e.plot(x, [abs(p.decay_error) * 100 for p in group], mk, color="tab:orange", ms=6, mfc="none")
        for j, p in enumerate(group):  # labels alternately above and below: neighbours often share a share
            ax_a.annotate(
                _value_label(p.axis, p.settings),
                (p.cpu_per_sim_second, p.agreement),
                fontsize=7,
                xytext=(4, 4 if j % 2 == 0 else -11),
                textcoords="offset points",
            )
    d, kn = frontier.points[frontier.default], frontier.points[frontier.knee]
    for p, style in (
        (d, {"s": 220, "facecolors": "none", "edgecolors": "k", "label": "defaults"}),
        (kn, {"s": 160, "marker": "*", "color": "gold", "edgecolors": "k", "label": "knee"}),
    ):
        if not p.error:
            ax_a.scatter([p.cpu_per_sim_second], [p.agreement], zorder=5, **style)
    ax_a.axhline(frontier.model_form_floor, color="grey", ls="--", lw=1, label="model-form floor")
    ax_a.set_xscale("log")
    ax_a.set_ylim(0.0, 1.0)
    ax_a.set_xlabel("CPU seconds per simulated second [s/s]")
    ax_a.set_ylabel("per-record agreement with Housner [-]")
    ax_a.set_title(f"{frontier.engine} on {frontier.scenario} ({frontier.n_motions} motions)", fontsize=10)
    ax_a.grid(True, alpha=0.3)
    ax_a.legend(fontsize=7, loc="upper left")
    ax_e.axhline(RTOL * 100, color="tab:blue", ls=":", lw=1, label=f"r tolerance {RTOL:.1%}")
    ax_e.axhline(DECAY_RTOL * 100, color="tab:orange", ls=":", lw=1, label=f"decay tolerance {DECAY_RTOL:.0%}")
    ax_e.plot([], [], "o", color="tab:blue", label="|r error|, 0.2-0.9 alpha")
    ax_e.plot([], [], "o", color="tab:orange", mfc="none", label="|decay error|, 40 impacts")
    ax_e.set_xscale("log")
    ax_e.set_yscale("log")
    ax_e.set_xlabel("CPU seconds per simulated second [s/s]")
    ax_e.set_ylabel("worst relative error [%]")
    ax_e.set_title("the tuner's checks", fontsize=10)
    ax_e.grid(True, alpha=0.3, which="both")
    ax_e.legend(fontsize=7, loc="best")
    return fig
