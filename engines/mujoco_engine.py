"""The rocking block in MuJoCo.

:class:`MujocoEngine` runs the planar model of :mod:`housner.engines.mjcf` (one body with slide x, slide z
and a hinge about y, touching the ground only at its two pivots), driven by the d'Alembert force of the
ground acceleration on an actuator of the x slide, the record stepped in C by :func:`mujoco.rollout.rollout`
(or from Python when an effect's terms act on the hinge, :mod:`housner.engines.mujoco_terms`). How it holds
the block and reads its response, and where it departs from the rigid block, are in
``docs/explanation/engines.md`` ("MuJoCo"); the contact settings and why, in :class:`MujocoEngine`; what
they measure and cost, in ``docs/results.md#defaults-mujoco``.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import mujoco
import numpy as np
from mujoco import rollout

from housner.engines._planar import ASYMMETRIC, IMPACT_LAW_RANGE, PlanarEngine, checked_settings, pivot_offset, pivot_x
from housner.engines.mjcf import MJCF_DEFAULTS, initial_qpos, mjcf_from_specimen
from housner.engines.mujoco_terms import (
    OWN_EFFECTS,
    THETA_DOF,
    RealisedEffects,
    moment_couple,
    roll_with_couple,
    term_refusal,
    terms_of,
)
from housner.errors import EngineError, unknown_choice
from housner.free_vibration.impacts import impact_times
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = ["MujocoEngine", "initial_qvel"]

#: A sign change of theta counts as an impact only if |theta| exceeded this
#: fraction of alpha since the previous sign change (the compliant contact
#: jitters at the micro-radian level at rest; 1e-3 alpha is 0.15 mrad for the
#: seed specimen, below its 0.8 mrad measurement resolution).
ROCKING_EPS = 1e-3

#: Simulated time per rollout chunk [s]; the run stops at the end of the chunk
#: in which the block overturns.
_CHUNK_S = 0.5

#: Chunk [s] while the impact law is on: a chunk is cut at each impact and the rest of it re-run,
#: so shorter chunks waste fewer steps.
_LAW_CHUNK_S = 0.02


def initial_qvel(
    specimen: Specimen, theta0: float, theta_dot0: float, pivot_radius: float = 0.0, offset: float = 0.0
) -> tuple[float, float, float]:
    """Joint velocities (vx [m/s], vz [m/s], theta_dot [rad/s]) of a block rotating about its pivot.

    The pivot is the +x one for theta0 > 0 (or theta0 = 0 and theta_dot0 > 0)
    and the -x one otherwise. The block rolls without slip on its pivot sphere
    of radius rho = ``pivot_radius`` [m] (0: the corner itself), so the
    instantaneous centre of rotation is the contact point (s B, 0) and the
    centre of mass moves as omega x r, with r the vector from that point to the
    centre of mass (placed by :func:`housner.engines.mjcf.initial_qpos`):
    (vx, vz) = theta_dot0 (r_z, -r_x). With the centre of mass ``offset`` e [m] toward +x of the pivots'
    midpoint the pivot's x, s B above, is B - e or -(B + e).
    """
    th, w = float(theta0), float(theta_dot0)
    if w == 0.0:
        return 0.0, 0.0, 0.0
    s = math.copysign(1.0, th) if th != 0.0 else math.copysign(1.0, w)
    H, rho = specimen.H, float(pivot_radius)
    bx = pivot_x(specimen.B, offset)[0 if s > 0.0 else 1]  # s B at offset 0
    # contact point -> centre of mass: sphere centre (s B, rho) -> centre of mass, upright (-s B, H - rho),
    # rotated by th about y: (x cos + z sin, -x sin + z cos); plus rho up from the contact to the sphere centre
    rx = -bx * math.cos(th) + (H - rho) * math.sin(th)
    rz = rho + bx * math.sin(th) + (H - rho) * math.cos(th)
    return w * rz, -w * rx, w


class MujocoEngine(PlanarEngine):
    """The planar rocking block in MuJoCo, driven by the d'Alembert force of the ground acceleration.

    Parameters
    ----------
    timestep : float
        Largest engine step [s]; the step used is motion.dt / ceil(motion.dt / timestep).
    solref : (float, float)
        Contact (timeconst [s], dampratio [-]) of the pivots and the ground, or
        MuJoCo's direct (-stiffness, -damping) when negative.
    solimp : 5 floats
        Contact impedance (dmin, dmax, width [m], midpoint, power) of the pivots and the ground.
    friction : float
        Friction coefficient mu of the pivots [-]; well above any max |ug''|/g
        of the records used (the seed's ground motions stay below 0.6 g).
    cone : {"pyramidal", "elliptic"}
        Friction cone.
    impratio : float
        Frictional-to-normal impedance ratio [-]; above 1 makes friction stiffer.
    noslip_iterations : int
        MuJoCo no-slip post-solver iterations (0 = off).
    impact_energy_factor : float
        The impact law's factor (:class:`housner.engines._planar.PlanarEngine`); 1 (default): the contact alone.
    integrator : {"Euler", "implicitfast", "implicit", "RK4"}
    iterations, tolerance : int, float
        Constraint-solver iterations and tolerance.
    strip_width, strip_height : float
        Size [m] of the drawn contact strips (the seed specimen's are 2 mm wide);
        their outer bottom edges are the pivots.
    pivot_radius : float
        Radius [m] of the contact spheres at the pivots (at most 1e-3 H).

    Notes
    -----
    MuJoCo's default contact (timestep 2 ms, solref (0.02, 1), elliptic cone,
    impratio 1) loses too much energy per impact (r 2 % low at 0.8 alpha, 7 %
    at 0.2 alpha) and lets the block rock too far under a pulse. The defaults
    (``DEFAULTS``) came from ``housner tune mujoco``
    (:func:`housner.engines.tuning.tune` over :meth:`tuning_candidates`) for the
    seed specimen and Housner's r; how the tuner chose them and what they
    measure, on the tuner's checks and on the seed's El Centro ensemble:
    docs/results.md#defaults-mujoco. What matters, and why:

    * The ground carries the pivots' ``solref`` and ``solimp``: MuJoCo averages
      the two geoms' values, and a ground at MuJoCo's default solref
      (0.02, 1) makes the contact's time constant 10 ms whatever the pivots
      ask. Such a soft contact lets the pivot sink by 2-18 um while the block
      rocks by a few mrad (its heel lifts by 2B theta = 75 um per mrad) and
      absorbs the energy of small impacts: r 3-15 % low below 0.02 alpha, the
      small rocking of a record dies out. In the first tuned model the ground
      did not carry them, and every contact was some 40 times softer than its
      settings said (``engines/models/README.md``, CHANGELOG).
    * ``timestep`` 0.2 ms with ``solref`` (0.4 ms, 1), two steps, critically
      damped: the coarsest step whose per-impact scatter passes the tuner at
      both sample steps (0.25 ms passed at one only).
    * ``cone="pyramidal"`` with ``impratio=10``: with a pyramidal cone MuJoCo
      regularises the whole contact in proportion to mu^2 / impratio; at
      impratio 1 the stiff contact still passes, but with less margin.
    * ``pivot_radius`` 10 um: one contact point per pivot (a box strip gives
      four), about 30 % less time per step than the strips; the block rolls
      on the sphere, which moves its pivot by rho = 4e-5 H.
    * ``friction`` 1.5 is set on the ground too (MuJoCo takes the larger of
      the two geoms' coefficients): far above the seed's ground motions
      (< 0.6 g) and the impacts' demand; the pivots slip by about 1 um.

    The calibrated r = 0.9532 of the seed (Table 1) is out of reach: the
    contact is plastic whatever its damping, and no candidate (including
    dampratio 0.1 and direct stiffness with little damping) raised the ratio
    above Housner's consistently; see ``engines/models/README.md``.

    References
    ----------
    MuJoCo documentation, "Computation": soft contacts, solref, solimp and solmix.
    Bachmann, J. A. et al. (2017). COMPDYN 2017, eq. 8 and Table 1.
    """

    name: ClassVar[str] = "mujoco"
    #: rotational_damping and restitution, and the registered effects realised through their moment terms
    effects_supported = RealisedEffects()  # the registry may grow after import

    #: Tuned defaults (see the class notes for their provenance and measured errors).
    DEFAULTS: ClassVar[dict] = {**MJCF_DEFAULTS, "impact_energy_factor": 1.0}
    #: The accuracy-cost frontier's axes (``housner frontier mujoco``): the step [s] and the contact's
    #: solref time constant [s] (its stiffness: the default 0.4 ms is twice the default step, MuJoCo's floor).
    FRONTIER: ClassVar[dict] = {
        "timestep": (1e-4, 2e-4, 3e-4, 5e-4),
        "solref": ((4e-4, 1.0), (6e-4, 1.0), (1e-3, 1.0)),
    }

    def __init__(self, **settings: Any):
        for key in settings:
            if key not in self.DEFAULTS:
                raise unknown_choice("MujocoEngine setting", key, self.DEFAULTS)
        merged = {**self.DEFAULTS, **settings}
        for key in ("solref", "solimp"):
            merged[key] = tuple(float(v) for v in merged[key])
        law = {"impact_energy_factor": merged["impact_energy_factor"]}
        law_range = {"impact_energy_factor": IMPACT_LAW_RANGE}
        merged.update(checked_settings(self.LABEL, {"impact_energy_factor": 1.0}, law_range, law, strict=tuple(law)))
        self._settings = merged
        # validate now with the seed specimen's geometry (again per specimen when simulating)
        self.mjcf(Specimen.bachmann2017())
        self._cache: dict = {}

    # ------------------------------------------------------------------
    def settings(self) -> dict:
        """The engine's settings as plain data (tuples as lists)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self._settings.items()}

    def version(self) -> str:
        """The MuJoCo package version."""
        return mujoco.__version__

    def mjcf(self, specimen: Specimen, offset: float = 0.0) -> str:
        """The MJCF text of ``specimen`` with this engine's settings, the pivots at x = B - e and -(B + e) of the
        centre of mass for ``offset`` e [m] (``asymmetric_pivots``; 0: the symmetric block)."""
        settings = {k: v for k, v in self._settings.items() if k in MJCF_DEFAULTS}
        if offset == 0.0:
            return mjcf_from_specimen(specimen, **settings)
        return mjcf_from_specimen(specimen, offset=offset, **settings)

    def _model(self, specimen: Specimen, offset: float = 0.0):
        key = specimen if offset == 0.0 else (specimen, offset)
        entry = self._cache.get(key)
        if entry is None:
            # a subclass's mjcf(specimen) of the symmetric block keeps its signature
            text = self.mjcf(specimen) if offset == 0.0 else self.mjcf(specimen, offset)
            model = mujoco.MjModel.from_xml_string(text)
            entry = (model, mujoco.MjData(model))
            self._cache[key] = entry
        return entry

    # ------------------------------------------------------------------
    @classmethod
    def tuning_candidates(cls, specimen: Specimen, target_r: float) -> list[dict]:
        """Settings to try when tuning the contact to an energy ratio, cheap to expensive.

        Steps of 1/2, 1/3, 1/4, 1/5, 1/6 and 1/8 ms (they divide the tuner's
        1 ms samples); for each, contact time constants of 2 and 4 steps
        (MuJoCo needs at least 2), MuJoCo's default impedance (0.9, 0.95, 1 mm)
        and a stiff one (0.99, 0.999, 0.1 mm), and the friction cone as
        pyramidal with impratio 1, 10 and 100 (with a pyramidal cone MuJoCo
        regularises the whole contact in proportion to mu^2 / impratio) or
        elliptic with impratio 1 and 100. The friction coefficient stays at its
        default: it is chosen to prevent sliding, not tuned. When the target
        lies above Housner's r, lightly damped contacts are added (dampratio
        0.1, and direct stiffness with little damping): the only knobs that
        could give energy back at an impact. Below Housner's r, over-damped
        contacts (dampratio 1-8) at the default step. Returns keyword settings of :class:`MujocoEngine`
        for ``target_r``, the target kinetic-energy ratio at impact [-].
        """
        soft = (0.9, 0.95, 0.001, 0.5, 2.0)
        stiff = (0.99, 0.999, 0.0001, 0.5, 2.0)
        if target_r < specimen.r_housner * 0.999:
            # Below Housner's r the only knob is the contact's damping: over-damped contacts at the
            # default step (what they reach: docs/results.md#defaults-mujoco). The
            # tuner then says how far below Housner's r MuJoCo gets.
            h = 2e-4
            return [dict(timestep=h, solref=(tc, dr)) for dr in (1.0, 2.0, 4.0, 8.0) for tc in (2 * h, 4 * h)]
        cones = [("pyramidal", 1.0), ("pyramidal", 10.0), ("pyramidal", 100.0), ("elliptic", 1.0), ("elliptic", 100.0)]
        above = target_r > specimen.r_housner * 1.001
        out = []
        for n in (2, 3, 4, 5, 6, 8):
            h = 1e-3 / n
            for tc in (2 * h, 4 * h):
                for dr in (1.0, 0.1) if above else (1.0,):
                    for solimp in (soft, stiff):
                        for cone, impratio in cones:
                            out.append(dict(timestep=h, solref=(tc, dr), solimp=solimp, cone=cone, impratio=impratio))
            if above:
                k = 1.0 / (2 * h) ** 2  # stiffness of timeconst 2h, dampratio 1 [1/s^2]
                for b in (100.0, 300.0):
                    out.append(dict(timestep=h, solref=(-k, -b), solimp=stiff, cone="pyramidal", impratio=100.0))
        return out

    # ------------------------------------------------------------------
    def effect_refusal(self, specimen: Specimen, effects: tuple) -> str | None:
        """Why MuJoCo cannot realise these (supported) effects on ``specimen``, or None.

        An effect realised through terms whose terms here are not all moment terms that vanish at rest
        (named), ``rotational_damping`` together with ``asymmetric_pivots`` (the hinge's damping is one
        c I, the effect's moment -c I+- theta' is per pivot), or a ``restitution`` above the contact's r.
        """
        names = {e.name for e in effects}
        if ASYMMETRIC in names and "rotational_damping" in names and pivot_offset(effects) != 0.0:
            return (
                f"engine {self.name!r} cannot realise 'rotational_damping' together with 'asymmetric_pivots': its "
                "hinge damping is one c I, while the moment -c I theta' of the effect takes the inertia about the "
                "pivot rocked on, which differs between the two pivots"
            )
        if any(e.name not in OWN_EFFECTS for e in effects):
            for e, terms in terms_of(specimen, effects)[1]:
                why = term_refusal(self.name, e, terms)
                if why:
                    return why
        return super().effect_refusal(specimen, effects)

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        e = pivot_offset(effects)
        model, data = self._model(specimen, e)
        # every call sets the hinge's damping (the model is cached per specimen): c I0 [N m s], 0 without the effect
        model.dof_damping[THETA_DOF] = sum(e.c for e in effects if e.name == "rotational_damping") * specimen.inertia
        n_sub = max(1, math.ceil(motion.dt / self._settings["timestep"] * (1.0 - 1e-12)))
        h = motion.dt / n_sub
        model.opt.timestep = h
        nstep = (motion.n - 1) * n_sub

        # d'Alembert force at the middle of each step, ug'' linear between samples
        t_mid = (np.arange(nstep) + 0.5) * h
        ctrl = (-specimen.mass * np.interp(t_mid, motion.t, motion.acc)).reshape(-1, 1)

        state = self._release(model, data, specimen, motion, e)
        i_q = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_TIME)
        i_v = i_q + model.nq

        # per-step histories, index 0 = initial state
        x = np.empty(nstep + 1)
        z = np.empty(nstep + 1)
        th = np.empty(nstep + 1)
        w = np.empty(nstep + 1)
        x[0], z[0], th[0], w[0] = data.qpos[0], data.qpos[1], data.qpos[2], data.qvel[2]
        chunk = max(1, round(_CHUNK_S / motion.dt)) * n_sub
        warm = np.zeros(model.nv)
        done = 0
        overturn_step = None
        law = self.impact_law(specimen, effects, h, motion.theta0)
        if law.active:
            chunk = min(chunk, max(n_sub, round(_LAW_CHUNK_S / h)))
        # the effects' moment terms as a couple on the hinge, evaluated before each step (None: the rollout alone)
        moment = moment_couple(specimen, motion, effects, h, nstep, e)
        while done < nstep:
            k1 = min(nstep, done + chunk)
            if moment is None:
                out, _ = rollout.rollout(model, data, state, ctrl[done:k1], initial_warmstart=warm)
                out = out[0]
            else:
                out = roll_with_couple(model, data, state, ctrl[done:k1], warm, moment[0], done)
            if law.active and (hit := law.first_scale(out[:, i_q + 2], out[:, i_v + 2])) is not None:
                # the chunk ends at the scaling's step; the next one starts from its scaled velocities
                j, c = hit
                out = out[: j + 1].copy()
                out[-1, i_v : i_v + model.nv] *= c
                k1 = done + 1 + j
                data.qacc_warmstart[:] = 0.0  # the warm start of a step not kept is no guide
            x[done + 1 : k1 + 1] = out[:, i_q]
            z[done + 1 : k1 + 1] = out[:, i_q + 1]
            th[done + 1 : k1 + 1] = out[:, i_q + 2]
            w[done + 1 : k1 + 1] = out[:, i_v + 2]
            self._check_chunk(out[:, i_q : i_v + model.nv], data, motion, done, k1, h)
            hit = np.flatnonzero(np.abs(th[done + 1 : k1 + 1]) >= math.pi / 2)
            state = out[-1].copy()
            warm = data.qacc_warmstart.copy()
            if hit.size:
                overturn_step = done + 1 + int(hit[0])
                done = k1
                break
            done = k1
        k = done + 1
        res = self._response(specimen, motion, x[:k], z[:k], th[:k], w[:k], h, n_sub, overturn_step, e)
        if moment is not None:
            res.info["terms"] = moment[1]  # as the analytic engine's Response.info lists them
        return res

    def _release(self, model, data, specimen: Specimen, motion: GroundMotion, offset: float = 0.0) -> np.ndarray:
        """Put ``data`` in the motion's initial state (its release: theta0 [rad], theta_dot0 [rad/s], about the
        pivot on its side with the centre of mass ``offset`` [m] toward +x of the pivots' midpoint) and
        return that state as MuJoCo's full physics state vector."""
        mujoco.mj_resetData(model, data)
        rho = self._settings["pivot_radius"]
        data.qpos[:] = initial_qpos(specimen, motion.theta0, rho, offset)
        data.qvel[:] = initial_qvel(specimen, motion.theta0, motion.theta_dot0, rho, offset)
        mujoco.mj_forward(model, data)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, data, state, spec)
        return state

    def _check_chunk(self, qv: np.ndarray, data, motion: GroundMotion, done: int, k1: int, h: float) -> None:
        """EngineError if the chunk of steps ``done + 1`` to ``k1`` (their positions and velocities ``qv``, one row
        a step of ``h`` [s]) diverged: a state that is not finite, or a warning other than a full contact buffer."""
        if not np.all(np.isfinite(qv)):
            bad = done + 1 + int(np.flatnonzero(~np.all(np.isfinite(qv), axis=1))[0])
            raise EngineError(
                f"MuJoCo diverged on motion {motion.name!r}: non-finite state at t = {bad * h:.6g} s "
                f"(settings {self.settings()})"
            )
        bad_warn = [
            mujoco.mjtWarning(i).name
            for i in range(len(data.warning))
            if data.warning[i].number
            and mujoco.mjtWarning(i) not in (mujoco.mjtWarning.mjWARN_CONTACTFULL, mujoco.mjtWarning.mjWARN_CNSTRFULL)
        ]
        if bad_warn:
            raise EngineError(
                f"MuJoCo diverged on motion {motion.name!r} before t = {k1 * h:.6g} s: warnings {bad_warn} "
                f"(settings {self.settings()})"
            )

    def _response(self, specimen, motion, x, z, th, w, h, n_sub, overturn_step, offset: float = 0.0) -> Response:
        """Assemble the Response from per-step histories (index 0 = initial state, step i at t = i h); the
        pivots at x = B - e and -(B + e) of the centre of mass, e = ``offset`` [m]."""
        alpha = specimen.alpha
        n = motion.n
        if overturn_step is not None:
            k = overturn_step
            # time at which |theta| reached pi/2, linear between steps
            a0, a1 = abs(th[k - 1]), abs(th[k])
            frac = (math.pi / 2 - a0) / (a1 - a0) if a1 != a0 else 1.0
            overturn_time = (k - 1 + min(max(frac, 0.0), 1.0)) * h
            sign = math.copysign(1.0, th[k])
            x, z, th, w = x[:k], z[:k], th[:k], w[:k]
        else:
            overturn_time = math.nan
        t_steps = np.arange(th.size) * h

        # samples on the motion's grid (held at +-pi/2 and at rest after an overturn)
        theta = np.empty(n)
        theta_dot = np.empty(n)
        idx = np.arange(n) * n_sub
        have = idx < th.size
        theta[have] = th[idx[have]]
        theta_dot[have] = w[idx[have]]
        if overturn_step is not None:
            after = motion.t >= overturn_time
            theta[after] = sign * math.pi / 2
            theta_dot[after] = 0.0

        eps = ROCKING_EPS * alpha
        impacts = impact_times(t_steps, th, eps)
        theta_max = math.pi / 2 if overturn_step is not None else float(np.max(np.abs(th)))
        B, H, rho = specimen.B, specimen.H, self._settings["pivot_radius"]
        bp, bn = pivot_x(B, offset)  # (B, -B) at offset 0
        # height of the bottom of the heel pivot sphere (centre (-s B, -H + rho) in the body frame, s = sgn th):
        # H + z + B |sin th| - (H - rho) cos th - rho; B is the heel's distance from the centre of mass
        b_heel = B if offset == 0.0 else np.where(th >= 0.0, -bn, bp)
        heel = H + z + b_heel * np.abs(np.sin(th)) - (H - rho) * np.cos(th) - rho
        uplift_time = _uplift_time(t_steps, th, heel, eps, released=motion.theta0 != 0.0 or motion.theta_dot0 != 0.0)

        # slip of the pivot the block stands on: its sphere's centre, at x + s B cos th - (H - rho) sin th, minus
        # where rolling without slip from (s B, rho) upright would put it, s B + rho th
        sb = np.where(th >= 0.0, bp, bn)  # s B, the x of the pivot stood on
        slip = np.abs(x + sb * np.cos(th) - (H - rho) * np.sin(th) - sb - rho * th)
        rocking = np.abs(th) <= alpha
        info = {
            "settings": self.settings(),
            "mujoco_version": self.version(),
            "timestep_used_s": h,
            "substeps_per_sample": n_sub,
            "n_steps": int(th.size - 1),
            "max_pivot_slip_m": float(np.max(slip[rocking])) if np.any(rocking) else math.nan,
            "max_pivot_slip_all_m": float(np.max(slip)),
        }
        return Response(
            t=motion.t.copy(),
            theta=theta,
            theta_dot=theta_dot,
            impact_times=impacts,
            theta_max=theta_max,
            alpha=alpha,
            overturned=overturn_step is not None,
            overturn_time=overturn_time,
            uplift_time=uplift_time,
            engine=self.name,
            info=info,
        )


def _uplift_time(t: np.ndarray, th: np.ndarray, heel: np.ndarray, eps: float, released: bool) -> float:
    """First time [s] the block left rest: the heel pivot's last lift-off before |theta| first exceeds ``eps``.

    0 for a block released off its rest position; NaN if |theta| never exceeds ``eps`` [rad].
    """
    if released:
        return 0.0
    above = np.flatnonzero(np.abs(th) > eps)
    if above.size == 0:
        return math.nan
    k = int(above[0])
    down = np.flatnonzero(heel[: k + 1] <= 0.0)
    if down.size == 0:
        return float(t[0])
    j = int(down[-1])  # last step with the heel on the ground; lift-off between j and j + 1
    a, b = heel[j], heel[j + 1]
    return float(t[j] + (t[j + 1] - t[j]) * (-a) / (b - a)) if b != a else float(t[j + 1])
