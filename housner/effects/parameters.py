"""Effects that change the rocking parameters (restitution, its amplitude dependence, rotational damping,
asymmetric pivots, frequency parameter)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from numba import njit

from housner._kernel_parts import clip_unit
from housner.effects.registry import (
    STAGE_DISSIPATION,
    STAGE_GEOMETRY,
    STAGE_INERTIA,
    Effect,
    param,
    register_effect,
)
from housner.effects.terms import ImpactTerm, MomentTerm
from housner.rocking_params import pivot_impact_ratios
from housner.specimen import Specimen
from housner.units import G


# ----------------------------------------------------------------------
# the same physics as kernel terms (the routes the tests compare with the parameter vector's)
@njit(cache=True)
def restitution_law(w, r, s, alpha, p2, q):
    """Energy ratio [-] of an impact that ends rocking on pivot s: q = (r_pos, r_neg), of the landing corner."""
    return q[1] if s > 0.0 else q[0]


@njit(cache=True)
def amplitude_law(w, r, s, alpha, p2, q):
    """r (w / (p alpha))^n clipped to [0, 1], q = (n,): :func:`housner._kernel_parts.restitution`'s arithmetic."""
    r_eff = r
    if q[0] != 0.0 and w > 0.0:
        r_eff = clip_unit(r * (w / (math.sqrt(p2) * alpha)) ** q[0])
    return r_eff


@njit(cache=True)
def damping_moment(phi, w, t, a, v, s, alpha, p2, q):
    """Viscous moment per unit I0 [rad/s^2], -c w, q = (c,) [1/s]."""
    return -(q[0] * w)


# ----------------------------------------------------------------------
# effects that change the rocking parameters
class _NeutralAtZero(Effect):
    """A fast-path dissipation effect of one parameter whose value 0 changes nothing.

    At a non-zero value v, ``modify_params`` gives the rocking parameters of :meth:`_realise` and
    ``terms`` the one kernel term of :meth:`_term`: the same physics by the two routes.
    """

    stage = STAGE_DISSIPATION
    fast_path = True

    def _value(self) -> float:
        (key,) = type(self).param_specs
        return getattr(self, key)

    def _realise(self, params, v: float):
        """The rocking parameters ``params`` with the effect of value ``v`` applied."""
        raise NotImplementedError

    def _term(self, v: float):
        """The effect of value ``v`` as a kernel term (:mod:`housner.effects.terms`)."""
        raise NotImplementedError

    def modify_params(self, params, specimen):
        v = self._value()
        return params if v == 0.0 else self._realise(params, v)

    def terms(self, params, specimen):
        v = self._value()
        return () if v == 0.0 else (self._term(v),)


@register_effect
@dataclass(frozen=True)
class Restitution(Effect):
    """Kinetic-energy ratio at impact r, free instead of Housner's value.

    At every impact theta'_after = sqrt(r) theta'_before, so the energy ratio
    of two successive free-rocking half-cycles is r (seed eq. 8 measures it
    as c_i = (cos(alpha - |theta_{i+1}|) - cos alpha) / (cos(alpha - |theta_i|)
    - cos alpha)). Neutral: the specimen's Housner value (seed eq. 4).

    Parameters
    ----------
    r : float
        Kinetic-energy ratio at impact [-], in [0, 1].

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 4 and 8 and Table 1
    (r = 0.9532 measured, 0.9465 from eq. 4).
    """

    name = "restitution"
    stage = STAGE_DISSIPATION
    fast_path = True
    r: float = param("-", (0.0, 1.0), neutral=lambda s: s.r_housner, doc="kinetic-energy ratio at impact")

    def modify_params(self, params, specimen):
        # with_r keeps the split of an asymmetric block's two impacts (r_pos / r_neg)
        return params.with_r(self.r)

    def terms(self, params, specimen):
        """The same law as an impact term: each landing corner's ratio of ``params.with_r(r)``."""
        p = params.with_r(self.r)
        return (ImpactTerm(restitution_law, (p.r_impact_pos, p.r_impact_neg), replaces=True),)


@register_effect
@dataclass(frozen=True)
class AmplitudeDependentRestitution(_NeutralAtZero):
    """Impact loss that depends on the impact speed.

    The energy ratio of an impact with pre-impact speed |theta'| is
    r_eff = clip(r (|theta'| / (p_s alpha_s))^n, 0, 1) with the r in force
    (Housner's or the ``restitution`` effect's), p_s and alpha_s of the
    corner the block rocked on before the impact. p alpha is the impact speed
    of a block released from theta = alpha in the linearised model, so a
    block released near overturning loses what r says; n > 0 makes small
    impacts lose more (tests on stone and concrete blocks find the measured
    ratio falling with amplitude), n < 0 less. Realised by
    ``RockingParams.r_amp_exponent``.

    Parameters
    ----------
    exponent : float
        Exponent n [-], in [-2, 2]; neutral 0 (constant r).

    References
    ----------
    Kalliontzis, D., Sritharan, S., Schultz, A. (2016). Improved coefficient
    of restitution estimation for free rocking members. Journal of Structural
    Engineering 142(12), 06016002.
    """

    name = "amplitude_dependent_restitution"
    exponent: float = param("-", (-2.0, 2.0), neutral=0.0, default=0.0, doc="exponent n of r (|theta'|/(p alpha))^n")

    def _realise(self, params, n: float):
        return replace(params, r_amp_exponent=n)

    def _term(self, n: float) -> ImpactTerm:
        """The same law as an impact term that scales the ratio in force."""
        return ImpactTerm(amplitude_law, (n,))


@register_effect
@dataclass(frozen=True)
class RotationalDamping(_NeutralAtZero):
    """Viscous moment between impacts, -c I0 theta'.

    The equation of motion gains -c theta', so between impacts the rocking
    energy per unit I0, E = theta'^2/2 + p^2 (cos(alpha - |theta|) - cos alpha)
    [1/s^2], decays at exactly dE/dt = -c theta'^2. A phenomenological stand-in
    for losses that Housner's instantaneous impact misses (air, interface
    micro-slip, a soft base). Adds to any damping already in force.

    Parameters
    ----------
    c : float
        Damping rate [1/s] per unit rotational inertia about the pivot, in
        [0, 5]; neutral 0.

    References
    ----------
    Housner (1963) for the energy integral.
    """

    name = "rotational_damping"
    c: float = param("1/s", (0.0, 5.0), neutral=0.0, default=0.0, doc="viscous damping rate of the rotation")

    def _realise(self, params, c: float):
        return replace(params, damping=params.damping + c)

    def _term(self, c: float) -> MomentTerm:
        """The same moment as a kernel term, -c w (zero at rest: the uplift rule is unchanged)."""
        return MomentTerm(damping_moment, (c,), at_rest=False)


def asymmetric_impact_ratios(specimen: Specimen, e: float) -> tuple[float, float]:
    """Angular-velocity ratios of the two impacts of a block whose centre of mass is off-centre.

    The centre of mass sits at height H and horizontally e [m] toward +x from
    the midpoint of the pivots, so the +x corner is b+ = B - e and the -x
    corner b- = B + e away from it horizontally. Conservation of angular
    momentum about the corner that lands (Housner's assumptions: impulse at
    the corner, no bounce, no slip) gives, with I_c the centroidal inertia and
    I+- = I_c + m (H^2 + b+-^2) the inertia about each corner::

        theta'_after / theta'_before = (I_c + m (H^2 - b+ b-)) / I_landing

    Returns
    -------
    (rho_pos_to_neg, rho_neg_to_pos) : tuple of float
        Ratio [-] for an impact that ends rocking on the +x corner and lands
        on the -x corner, and for the reverse. For e = 0 both are
        1 - 2 m B^2 / I0 = sqrt(r_housner).
    """
    return pivot_impact_ratios(specimen.B - e, specimen.B + e, specimen.H, specimen.centroidal_inertia, specimen.mass)


@register_effect
@dataclass(frozen=True)
class AsymmetricPivots(Effect):
    """Centre of mass off-centre by e: the two corners have their own alpha, R and p.

    With the centre of mass e [m] toward +x of the midpoint of the pivots
    (height H, centroidal inertia I_c unchanged), the block rocking on the +x
    corner (theta > 0) has b+ = B - e, alpha+ = atan(b+/H), R+ = hypot(b+, H),
    p+ = sqrt(m g R+ / (I_c + m R+^2)); on the -x corner the same with
    b- = B + e. The uplift thresholds differ: it lifts onto the +x corner when
    ug'' < -g tan(alpha+) and onto the -x corner when ug'' > g tan(alpha-).

    Impacts: angular momentum about the landing corner is conserved
    (:func:`asymmetric_impact_ratios`): just before an impact that ends
    rocking on the +x corner, the block turns at theta' about that corner;
    the impulse acts at the landing (-x) corner, so the angular momentum
    about it, (I_c + m (H^2 - b+ b-)) theta', is kept, and just after the
    block turns about the -x corner with inertia I- = I_c + m (H^2 + b-^2).
    This scales theta' by rho+- at that impact and by rho-+ (the same with
    the sides swapped) at the converse; rho+- / rho-+ = I+ / I-. The effect
    sets the restitution of each impact exactly (``RockingParams.r_pos`` and
    ``r_neg``, ratios of the squared angular velocities; the kinetic energy
    itself changes by rho+-^2 I- / I+ and rho-+^2 I+ / I-)::

        r_neg = rho+-^2 * r_in_force(-) / r_housner   (lands on the -x corner)
        r_pos = rho-+^2 * r_in_force(+) / r_housner   (lands on the +x corner)
        r     = rho+- rho-+ * r_in_force / r_housner  (their geometric mean)

    each clipped to 1, where r_in_force is the ratio in force before this
    effect (per side where set). With Housner's r in force this is
    r_neg = rho+-^2 and r_pos = rho-+^2; a later ``restitution`` effect
    rescales both (:meth:`housner.rocking_params.RockingParams.with_r`), keeping
    r_neg / r_pos = (I+ / I-)^2.

    Parameters
    ----------
    e : float
        Horizontal offset of the centre of mass toward +x [m]; neutral 0.
        Any |e| < B (B the half width) is accepted, so that both pivots stay
        on their side of the centre of mass (b+ and b- > 0: the block stands
        upright); the parameter's bounds, +-B/2, are the range the diagnosis
        searches (:func:`housner.scenarios.diagnosis.selection.fitting.param_dims`), not
        a physical limit (a scanned rock's equivalent block may need more:
        e / B = 0.70 for the ASU granite SP1).

    References
    ----------
    Housner (1963) for the impact law (angular momentum about the new pivot);
    the asymmetric generalisation is derived in this docstring.
    """

    name = "asymmetric_pivots"
    stage = STAGE_GEOMETRY
    e: float = param(
        "m", lambda s: (-0.5 * s.B, 0.5 * s.B), neutral=0.0, default=0.0, doc="offset of the centre of mass toward +x"
    )

    def check(self, specimen: Specimen) -> None:
        """ValueError naming ``e`` unless |e| < B of ``specimen`` (b+ = B - e and b- = B + e both positive).

        The bounds +-B/2 of the parameter are the diagnosis' search range only (see the class docstring).
        """
        B = specimen.B
        if not abs(self.e) < B:
            raise ValueError(
                f"`e` of effect {self.name!r} must lie in (-{B:g}, {B:g}) m for specimen {specimen.name!r} "
                f"(|e| < B: both pivots on their side of the centre of mass), got {self.e!r}"
            )

    def modify_params(self, params, specimen):
        if self.e == 0.0:
            return params
        m, hh, ic = specimen.mass, specimen.H, specimen.centroidal_inertia
        out = {}
        for side, b in (("pos", specimen.B - self.e), ("neg", specimen.B + self.e)):
            rr = math.hypot(b, hh)
            out[f"alpha_{side}"] = math.atan2(b, hh)
            out[f"p_{side}"] = math.sqrt(m * G * rr / (ic + m * rr * rr))
        rho_pn, rho_np = asymmetric_impact_ratios(specimen, self.e)
        r_h = specimen.r_housner
        out["r"] = min(1.0, params.r * rho_pn * rho_np / r_h)
        out["r_neg"] = min(1.0, params.r_impact_neg * rho_pn * rho_pn / r_h)  # lands on the -x corner
        out["r_pos"] = min(1.0, params.r_impact_pos * rho_np * rho_np / r_h)  # lands on the +x corner
        return replace(params, **out)


@register_effect
@dataclass(frozen=True)
class FrequencyParameter(Effect):
    """The frequency parameter p scaled by a factor (a mis-stated or mis-measured p).

    Both corners' p are multiplied by ``factor``: half-cycle durations scale
    as 1/factor (Housner: cosh(p T / 4) = 1 / (1 - theta0/alpha), seed eq. 7).
    alpha and r are unchanged (change r with ``restitution``). To state p
    directly use :meth:`from_p`.

    Parameters
    ----------
    factor : float
        Ratio of the p used to the specimen's p [-], in [0.5, 2]; neutral 1.

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 3 and 7 (p calibrated from
    free vibration, 4.8883 1/s).
    """

    name = "frequency_parameter"
    stage = STAGE_INERTIA
    factor: float = param("-", (0.5, 2.0), neutral=1.0, default=1.0, doc="ratio of the p used to the specimen's p")

    @classmethod
    def from_p(cls, specimen: Specimen, p: float) -> FrequencyParameter:
        """The effect that makes the specimen rock with frequency parameter ``p`` [1/s]."""
        if not (isinstance(p, (int, float)) and math.isfinite(p) and p > 0):
            raise ValueError(f"`p` must be a positive number [1/s], got {p!r}")
        return cls(factor=p / specimen.frequency_parameter)

    def modify_params(self, params, specimen):
        if self.factor == 1.0:
            return params
        return replace(params, p_pos=params.p_pos * self.factor, p_neg=params.p_neg * self.factor)
