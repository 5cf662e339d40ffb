"""Sliding: a block on rigid ground with Coulomb friction; rest, slide, rock, slide-rock (effect and driver; the
kernel is :mod:`housner.effects._sliding_kernel`)."""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np

from housner.effects._mechanics import MAX_EVENTS_PER_SAMPLE, corner_geometry, pos_int_or_none, run_kernel
from housner.effects._sliding_kernel import (
    N_SLIDE,
    S_ALPHA_N,
    S_ALPHA_P,
    S_C,
    S_G,
    S_I0_N,
    S_I0_P,
    S_MU,
    S_P2_N,
    S_P2_P,
    S_R,
    S_R_N,
    S_R_P,
    S_REXP,
    run_sliding,
)
from housner.effects.registry import STAGE_MECHANICS, Effect, param, register_effect
from housner.model import default_substeps
from housner.motion import GroundMotion
from housner.response import Response
from housner.rocking_params import RockingParams
from housner.specimen import Specimen
from housner.units import G


def simulate_sliding(
    specimen: Specimen,
    motion: GroundMotion,
    params=None,
    *,
    mu: float,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
) -> Response:
    """Rocking with Coulomb friction at the base (see :class:`Sliding` for the model).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
        Ground acceleration [m/s^2] and initial state theta0 [rad],
        theta_dot0 [rad/s] (the base is not slipping at t = 0).
    params : RockingParams, optional
        Every field is used except the per-side ratios ``r_pos`` and
        ``r_neg`` (the sliding kernel's impacts use ``r``, the geometric mean
        of the two for :class:`AsymmetricPivots`); default: the specimen's.
    mu : float
        Friction coefficient [-].
    substeps : int, optional
        RK4 substeps per sample; default as :func:`housner.model.simulate` (p h <= 0.01).
    rest_tol : float
        Rest rule of :func:`housner.model.simulate` [-].

    Returns
    -------
    Response
        ``info`` adds ``slip`` (horizontal displacement of the base corner in
        contact relative to the ground [m], history), ``regime`` (int8
        history: 0 rest, 1 slide, 2 rock, 3 slide-rock, 4 overturned),
        ``slip_max`` [m], ``slide_time`` (first slip [s], NaN if none),
        ``painleve_jams`` and ``lift_off_time`` [s] (see :class:`Sliding`).
    """
    prm = RockingParams.from_specimen(specimen) if params is None else params
    mu = float(mu)
    if not (math.isfinite(mu) and mu > 0):
        raise ValueError(f"`mu` must be positive and finite, got {mu!r}")
    if not (isinstance(rest_tol, (int, float)) and 0.0 < rest_tol < 1.0):
        raise ValueError(f"`rest_tol` must lie in (0, 1), got {rest_tol!r}")
    geo = corner_geometry(specimen, prm)
    q = np.zeros(N_SLIDE)
    q[S_G], q[S_MU], q[S_C], q[S_R], q[S_REXP] = G, mu, prm.damping, prm.r, prm.r_amp_exponent
    for side, (ia, ir, ii, ip) in (
        ("pos", (S_ALPHA_P, S_R_P, S_I0_P, S_P2_P)),
        ("neg", (S_ALPHA_N, S_R_N, S_I0_N, S_P2_N)),
    ):
        _b, rr, i0, _ic = geo[side]
        q[ia] = getattr(prm, f"alpha_{side}")
        q[ir] = rr
        q[ii] = i0
        q[ip] = getattr(prm, f"p_{side}") ** 2
    m = pos_int_or_none("substeps", substeps)
    if m is None:
        m = default_substeps(prm.p_max, motion.dt)
    n = motion.n
    th, thd, x = np.empty(n), np.empty(n), np.empty(n)
    reg = np.empty(n, dtype=np.int8)
    acc_g = np.ascontiguousarray(motion.acc, dtype=np.float64) / G
    args = (acc_g, motion.dt, m, q, motion.theta0, motion.theta_dot0, float(rest_tol))
    chatter = f"sliding: more than {MAX_EVENTS_PER_SAMPLE} regime changes in one sample on motion {motion.name!r}"
    out, (imp,) = run_kernel(run_sliding, args, (th, thd, x, reg), 1, chatter)
    x_max, t_slide, n_jam, t_lift = out[6:]
    info = {
        "kernel": "sliding",
        "substeps": m,
        "rest_tol": rest_tol,
        "params": asdict(prm),
        "mu": mu,
        "slip": x,
        "regime": reg,
        "slip_max": float(x_max),
        "slide_time": float(t_slide),
        "painleve_jams": int(n_jam),
        "lift_off_time": float(t_lift),
    }
    return Response.from_kernel(motion.t, th, thd, imp, out, specimen.alpha, info)


@register_effect
@dataclass(frozen=True)
class Sliding(Effect):
    """Rocking with Coulomb friction mu at the base: rest, slide, rock and slide-rock.

    Rigid block, rigid ground; degrees of freedom theta and the horizontal
    slip x of the base corner in contact (the pivot stays on the ground, as in
    Housner's model). Friction F <= mu N, N the normal force. Regimes:

    * rest: the block moves with the ground while |ug''| <= mu g and it does
      not uplift (ug'' within [-g tan(alpha+), g tan(alpha-)]);
    * slide (theta = 0): m x'' = -m ug'' - mu m g sgn(x'); it stops when x'
      returns to zero and |ug''| <= mu g;
    * rock (x' = 0): Housner's equation; the pivot holds while the friction
      demand F = m (ug'' + zeta theta'' - xi theta'^2) stays within mu N,
      N = m (g - xi theta'' - zeta theta'^2), where (xi, zeta) = position of the
      centre of mass relative to the pivot;
    * slide-rock: both; with F = -mu N sgn(x') the moment balance about the
      pivot gives (I_c + m xi^2 + mu sgn(x') m zeta xi) theta'' =
      m (mu sgn(x') zeta + xi)(g - zeta theta'^2) - c I0 theta'. When this
      coefficient is not positive the Coulomb problem has no consistent slip
      (Painleve's paradox): the slip is stopped (a tangential jam, counted in
      ``info['painleve_jams']``). When the normal-force demand turns negative
      (the block would jump) friction vanishes and the pivot is kept on the
      ground (time counted in ``info['lift_off_time']``).

    Impacts follow Housner's law (theta' times sqrt(r), with every
    restitution effect) and keep the slip velocity: with x' unchanged,
    angular momentum about the landing corner is conserved exactly as on a
    fixed base, and the impulse lies inside the friction cone whenever
    mu >= tan(alpha) (it needs (1 - sqrt r) / ((1 + sqrt r) tan(alpha)) < tan(alpha)).

    Start of motion from rest under horizontal ground acceleration (Shenton
    1996): the block slides if mu < tan(alpha) and |ug''| > mu g, and then
    never rocks (friction caps the inertia force the base can transmit at
    mu m g < m g tan(alpha)); it rocks if mu > tan(alpha) and |ug''| > g tan(alpha),
    and slides while rocking when the friction demand exceeds mu N.

    Parameters
    ----------
    mu : float
        Coulomb friction coefficient at the base [-], in [0.01, 2]; neutral inf
        (no sliding: Housner's model).

    References
    ----------
    Shenton, H. W., Jones, N. P. (1991). Base excitation of rigid bodies. I:
    Formulation. Journal of Engineering Mechanics 117(10), 2286-2306.
    Shenton, H. W. (1996). Criteria for initiation of slide, rock, and
    slide-rock rigid-body modes. Journal of Engineering Mechanics 122(7), 690-693.
    Zhang, J., Makris, N. (2001). Rocking response of free-standing blocks
    under cycloidal pulses. Journal of Engineering Mechanics 127(5), 473-483.
    Genot, F., Brogliato, B. (1999). New results on Painleve paradoxes.
    European Journal of Mechanics A/Solids 18(4), 653-677.
    """

    name = "sliding"
    stage = STAGE_MECHANICS
    changes_mechanics = True
    mu: float = param("-", (0.01, 2.0), neutral=math.inf, doc="Coulomb friction coefficient at the base")

    def solver(self):
        if math.isinf(self.mu):
            return None
        return functools.partial(simulate_sliding, mu=self.mu)
