"""Pieces shared by the effects that change the mechanics: argument checks, corner geometry, the
compiled pieces of their kernels (the event bracketing), and the driver that runs a kernel.

Compiled equations of motion for the effects that change the mechanics (private).

Two hybrid (piecewise-smooth) systems, both integrated with classic RK4 on
steps aligned to the motion's samples (ground acceleration linear inside a
sample interval). Each has a discrete *mode* (pivot side, contacts, slip
direction); within a step the mode is frozen, so the right-hand side is
smooth and RK4 keeps its order. A step whose end state violates the mode
(a *margin* turns negative) is cut at the first violation, found by
bracketing (Illinois false position with bisection safeguard) on the length
of one RK4 step from the start of the step, to machine precision; the mode
is then updated and the step resumed. See :mod:`housner.effects` for the
physics and the public entry points.

* ``run_flexible``: a block on two compression-only spring-dashpots at its
  corners (vertical displacement w of the base point below the centre of
  mass, and rotation theta).
* ``run_sliding``: a block on rigid ground with Coulomb friction (pivot slip
  x and rotation theta), regimes rest, slide, rock and slide-rock.

Units: SI, angles [rad]; ``run_sliding`` takes the ground acceleration in
units of g [-] like :mod:`housner._kernel`, ``run_flexible`` in m/s^2.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from housner.errors import EngineError
from housner.specimen import Specimen
from housner.units import G


def pos_int_or_none(name: str, v) -> int | None:
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
        raise ValueError(f"`{name}` must be a positive integer, got {v!r}")
    return int(v)


def corner_geometry(specimen: Specimen, params) -> dict:
    """Per-unit-mass geometry of the two corners from the rocking parameters.

    Returns b (horizontal distance centre of mass -> corner [m]), R [m],
    i0 = I_corner / m [m^2] and i_c = I_c / m [m^2] per side; raises a
    ValueError when p implies an impossible inertia (I0 < m R^2).
    """
    hh = specimen.H
    out = {}
    for side in ("pos", "neg"):
        alpha = getattr(params, f"alpha_{side}")
        p = getattr(params, f"p_{side}")
        b = hh * math.tan(alpha)
        rr = math.hypot(b, hh)
        i0 = G * rr / (p * p)
        if i0 <= rr * rr:
            raise ValueError(
                f"`p_{side}` = {p:.6g} 1/s is impossible for a block with R = {rr:.6g} m (it must stay below "
                f"sqrt(g/R) = {math.sqrt(G / rr):.6g} 1/s): flexible_foundation and sliding need a positive centroidal "
                "inertia I0 - m R^2 (is the frequency_parameter `factor` too large?)"
            )
        out[side] = (b, rr, i0, i0 - rr * rr)
    return out


def run_kernel(kernel, args: tuple, histories: tuple, n_buffers: int, chatter: str):
    """Run a mechanics kernel recording its histories; rerun it without them if its impact buffers overflow.

    ``kernel(*args, record, *histories, *buffers)`` returns (theta_max,
    overturned, t_over, t_uplift, n_impacts, guard, ...) and fills ``n_buffers``
    per-impact buffers (impact times first), here max(64, n) long for n
    samples. A guard trip (chattering) raises EngineError(``chatter``).
    Returns the kernel's summary and the buffers cut to the impacts.
    """
    cap = max(64, histories[0].size)
    buffers = [np.empty(cap) for _ in range(n_buffers)]
    out = kernel(*args, True, *histories, *buffers)
    if out[5]:
        raise EngineError(chatter)
    n_imp = out[4]
    if n_imp > cap:
        buffers = [np.empty(n_imp) for _ in range(n_buffers)]
        kernel(*args, False, *(h[:0] for h in histories), *buffers)
    return out, [b[:n_imp].copy() for b in buffers]


#: Most mode changes allowed in one sample interval before the kernel gives up
#: (chattering); the Python side turns it into an EngineError.
MAX_EVENTS_PER_SAMPLE = 20_000


@njit(cache=True)
def illinois(h, v, hl, vl, hr, vr, side):
    """The bracket after trial h with value v (Illinois false position).

    h replaces the right end when v < 0 (``side`` -1), else the left end
    (``side`` +1); an end kept twice in a row has its value halved.
    Returns (hl, vl, hr, vr, side).
    """
    if v < 0.0:
        hr = h
        vr = v
        if side == -1:
            vl *= 0.5
        side = -1
    else:
        hl = h
        vl = v
        if side == 1:
            vr *= 0.5
        side = 1
    return hl, vl, hr, vr, side
