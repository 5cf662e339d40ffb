"""MuJoCo's route for the effects' terms: which effects it realises through them, and their couple on the hinge.

Term effects (:mod:`housner.effects.terms`) whose terms are all moment terms that vanish at rest
(``MomentTerm(..., at_rest=False)``) are realised as a couple s I0 (sum of the terms) on the theta hinge
(``data.qfrc_applied``), evaluated before each engine step from MuJoCo's state in the kernel's reduced
coordinates and stepped from Python (``mj_step``); every other effect is refused by name. How the couple is
evaluated, and why each refused kind is refused, are in ``docs/explanation/engines.md`` ("MuJoCo's route for
the effects' terms"); ``tests/test_mujoco_terms.py`` checks the realised ones against the analytic engine.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from housner.effects import EFFECTS, Effect, discover_effects
from housner.effects.terms import CoulombTerm, ImpactTerm, MomentTerm, TermSet
from housner.motion import GroundMotion
from housner.rocking_params import RockingParams
from housner.specimen import Specimen
from housner.units import G

#: Degree of freedom of the theta hinge (joints x, z, theta, one dof each).
THETA_DOF = 2

#: Effects with a route of their own (hinge damping, the impact law, the pivots' places); the others are realised
#: through their terms.
OWN_EFFECTS = frozenset({"rotational_damping", "restitution", "asymmetric_pivots"})

#: The hooks of an effect realised through its terms that must stay :class:`housner.effects.Effect`'s no-ops.
_NO_OP_HOOKS = ("modify_params", "transform_input", "observe", "solver")

#: Effect class -> whether MuJoCo realises it through its terms (:func:`_realised_by_terms`).
_BY_TERMS: dict[type, bool] = {}


def term_refusal(engine: str, effect: Any, terms: tuple) -> str | None:
    """One line naming ``effect`` when one of its ``terms`` is not a moment term that vanishes at rest, else None."""
    for t in terms:
        if isinstance(t, MomentTerm) and not t.at_rest:
            continue
        if isinstance(t, CoulombTerm):
            what = "a Coulomb term (a dry moment that holds the block; a joint frictionloss creeps instead)"
        elif isinstance(t, ImpactTerm):
            what = "an impact term (MuJoCo's contact makes the impacts)"
        elif isinstance(t, MomentTerm):
            what = "a moment term that acts at rest (at_rest=True: it changes the uplift rule)"
        else:
            what = f"a {type(t).__name__}"
        return (
            f"engine {engine!r} cannot realise effect {effect.name!r}: its terms include {what}; "
            "it realises moment terms that vanish at rest only"
        )
    return None


def _active_value(spec: Any, specimen: Specimen) -> float:
    """A value [spec.unit] of a parameter at which its effect acts: its default, else an end or the middle of its
    bounds, the first that differs from the neutral value (the neutral value when none does)."""
    neutral = spec.neutral_for(specimen)
    lo, hi = spec.bounds_for(specimen)
    for x in (spec.default, hi, lo, 0.5 * (lo + hi)):
        if x is not None and math.isfinite(x) and x != neutral:
            return float(x)
    return neutral


def _realised_by_terms(cls: type) -> bool:
    """Whether MuJoCo realises the effect class ``cls`` through its terms (decided once per class).

    Its only hook is ``terms`` (no change of the parameters, the input, the sensors or the equation of
    motion), it reads and makes no motion channel, and with every parameter active
    (:func:`_active_value`) on the seed specimen it returns terms, all of them moment terms that vanish
    at rest. A class that fails to build or to give terms there is not realised.
    :meth:`MujocoEngine.effect_refusal` checks each instance's own terms on the specimen simulated.
    """
    ok = _BY_TERMS.get(cls)
    if ok is not None:
        return ok
    ok = (
        not cls.changes_mechanics
        and not cls.channels
        and not cls.makes_channels
        and cls.terms is not Effect.terms
        and all(getattr(cls, h) is getattr(Effect, h) for h in _NO_OP_HOOKS)
    )
    if ok:
        seed = Specimen.bachmann2017()
        try:
            effect = cls(**{k: _active_value(p, seed) for k, p in cls.param_specs.items()})
            terms = tuple(effect.terms(RockingParams.from_specimen(seed), seed))
            ok = bool(terms) and term_refusal("mujoco", effect, terms) is None
        except Exception:  # a user's effect that breaks here is not realised; it must not break the others
            ok = False
    _BY_TERMS[cls] = ok
    return ok


class RealisedEffects:
    """``effects_supported`` read live from the effect registry (it may grow after import), on the class and on
    instances: the effects with a route of their own and those realised through their moment terms."""

    def __get__(self, obj: Any, objtype: Any = None) -> frozenset[str]:
        discover_effects()
        return OWN_EFFECTS | frozenset(n for n, cls in tuple(EFFECTS.items()) if _realised_by_terms(cls))


def terms_of(specimen: Specimen, effects: tuple) -> tuple[Any, list]:
    """The rocking parameters and, for each effect realised through terms, (effect, its terms).

    As :func:`housner.effects.apply_effects` forms them: the parameters after every ``modify_params`` in the
    order of the stages, then each effect's ``terms`` from them, in that order.
    """
    ordered = sorted(effects, key=lambda e: e.stage)
    prm = RockingParams.from_specimen(specimen)
    for e in ordered:
        prm = e.modify_params(prm, specimen)
    out = []
    for e in ordered:
        if e.name not in OWN_EFFECTS:
            e.check(specimen)
            out.append((e, tuple(e.terms(prm, specimen))))
    return prm, out


def moment_couple(
    specimen: Specimen, motion: GroundMotion, effects: tuple, h: float, nstep: int, offset: float = 0.0
) -> tuple | None:
    """The couple of the effects' moment terms on the theta hinge, and the terms described; None without terms.

    Returns ``(couple, described)``: ``couple(i, theta, theta_dot) -> float`` is the couple [N m] over engine
    step i (of length ``h`` [s], from t = i h) from the state at its start, theta [rad] and theta_dot [rad/s]:
    s I0 times the sum of the terms [rad/s^2] in the kernel's reduced coordinates on pivot
    s = sgn(theta) (sgn(theta_dot) at theta = 0): phi = s theta, w = s theta_dot, a = s ug''(i h)/g,
    v = 0, alpha and p^2 of pivot s. I0 = ``specimen.inertia`` [kg m^2] is the model's inertia about a
    pivot (the rocking parameters of an effect MuJoCo realises are the specimen's, p^2 = m g R / I0), so the
    couple turns the block with the acceleration the terms give; a generalised force on theta is a pure
    couple, the same moment about the pivot as about the centre of mass. With the centre of mass ``offset``
    e [m] toward +x of the pivots' midpoint (``asymmetric_pivots``) I0 is the inertia about pivot s,
    I_c + m (H^2 + b_s^2) with b+ = B - e, b- = B + e, and alpha, p of pivot s are those the effect sets.
    """
    if all(e.name in OWN_EFFECTS for e in effects):
        return None
    prm, by_effect = terms_of(specimen, effects)
    terms = tuple(t for _e, ts in by_effect for t in ts)
    if not terms:
        return None
    fns = tuple((t.fn, np.array(t.q, dtype=np.float64)) for t in terms)
    if offset == 0.0:
        i_pos = i_neg = specimen.inertia
    else:
        m, hh, ic = specimen.mass, specimen.H, specimen.centroidal_inertia
        i_pos, i_neg = (ic + m * (hh * hh + b * b) for b in (specimen.B - offset, specimen.B + offset))
    pos = (prm.alpha_pos, prm.p_pos * prm.p_pos, i_pos)
    neg = (prm.alpha_neg, prm.p_neg * prm.p_neg, i_neg)
    t_start = np.arange(nstep) * h
    times = t_start.tolist()
    ug = (np.interp(t_start, motion.t, motion.acc) / G).tolist()  # ug''/g at the start of each step [-]

    def couple(i: int, theta: float, theta_dot: float) -> float:
        if theta > 0.0 or (theta == 0.0 and theta_dot >= 0.0):
            s, (alpha, p2, i0) = 1.0, pos
        else:
            s, (alpha, p2, i0) = -1.0, neg
        phi, w, t, a = s * theta, s * theta_dot, times[i], s * ug[i]
        acc = 0.0
        for fn, q in fns:
            acc += fn(phi, w, t, a, 0.0, s, alpha, p2, q)
        return s * i0 * acc

    return couple, TermSet(terms).describe()


def roll_with_couple(
    model: Any, data: Any, state: np.ndarray, ctrl: np.ndarray, warm: np.ndarray, couple: Any, first: int
) -> np.ndarray:
    """One chunk as :func:`mujoco.rollout.rollout` runs it, with the couple [N m] on the theta hinge.

    The chunk's steps are steps ``first``, ``first + 1``, ... of the record; before each, ``couple(i,
    theta, theta_dot)`` is evaluated from the state and set in ``data.qfrc_applied`` (reset to 0 at the
    end). Returns the full physics state after each step, rollout's ``out[0]``; with a zero couple it is
    the rollout's, bit for bit (``tests/test_mujoco_terms.py``).
    """
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    mujoco.mj_setState(model, data, state, spec)
    data.qacc_warmstart[:] = warm
    out = np.empty((ctrl.shape[0], state.size))
    qpos, qvel, qfrc, dctrl = data.qpos, data.qvel, data.qfrc_applied, data.ctrl
    try:
        for i in range(ctrl.shape[0]):
            dctrl[:] = ctrl[i]
            qfrc[THETA_DOF] = couple(first + i, float(qpos[THETA_DOF]), float(qvel[THETA_DOF]))
            mujoco.mj_step(model, data)
            mujoco.mj_getState(model, data, out[i], spec)
    finally:
        qfrc[THETA_DOF] = 0.0
    return out
