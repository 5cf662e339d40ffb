"""A second, independent generator of synthetic measurement campaigns with a known ("true") physical effect.

Its purpose is to check that :func:`housner.scenarios.diagnose` holds on data that none of the project's own
code produced. It is written from the equations alone: nothing is imported or copied from :mod:`housner` nor
from ``tests/campaign_generators.py`` (the first generator); the effects' docstrings in
``housner/effects`` were read only for each effect's physical definition and parameterisation.

Specimen (Bachmann et al. 2017, the seed paper): 2H = 0.5 m (pivot line to top), 2B = 0.075 m (between the
pivots, tan(alpha) = B/H = 0.15), depth 0.4 m, m = 3.94 kg, p = 4.8883 1/s (measured). Convention for the
inertia: p is the measured quantity and defines the inertia about a pivot, p^2 = m g R / I0, so
I0 = m g R / p^2 = 0.4087 kg m^2 (R = hypot(B, H) = 0.2528 m, g = 9.80665 m/s^2); the centroidal inertia is
I_c = I0 - m R^2. Housner's impact keeps the angular momentum about the landing corner, which for a
symmetric block gives theta'_after / theta'_before = 1 - 2 m B^2 / I0 and the energy ratio
r = (1 - 2 m B^2 / I0)^2 = (1 - 2 B^2 p^2 / (g R))^2 = 0.9465 (seed Table 1). (A solid rectangle,
I0 = 4/3 m R^2, would give r = (1 - 3/2 sin^2 alpha)^2 = 0.935 and p = 5.39 1/s: the measured p says the
specimen is not one.)

Equation of motion, in physical form (not the reduced coordinate of the library), with s = sgn(theta) the
pivot (s = +1: the +x corner) and d = s alpha_s - theta::

    I0_s theta'' = -m (g + a_v) R_s sin(d) - m ug'' R_s cos(d) - c I0_s theta' - M_f sgn(theta')

(a_v: vertical table acceleration, only in ``vertical_table``; c: viscous rate; M_f: Coulomb pivot moment).
theta > 0 leans toward +x; a ground acceleration below -(g + a_v) tan(alpha+) lifts the block onto its +x
corner, above (g + a_v) tan(alpha-) onto its -x corner (campaign-format.md).

Mechanics beyond that equation (choices where the library's docstrings leave room are marked *)
* Flexible foundation: the library's two-spring model (theta and the vertical displacement w of the base
  point below the centre of mass; the corner on the side of sgn(theta) held horizontally; per corner
  k = m (2 pi f)^2 / 2 and c = zeta m 2 pi f), its equations derived here with Lagrange's equations. *A
  corner pushes while min(d, k d + c d') > 0 (pressed in and in compression). *A release starts with the
  weight on the springs: both corners at theta = 0, the lower corner alone carrying m g when tilted. No rest
  rule and no restitution (the springs replace them).
* Sliding: only mu < tan(alpha) (Shenton 1996: from rest the block slides, never rocks, so theta stays 0
  under a ground motion). *The free vibrations rock with the pivot held; the friction demand |F|/N is
  checked at every step (an error if it ever exceeds mu: slide-rock is not modelled), and mu must exceed a
  Housner impact's impulse ratio (1 - rho) / ((1 + rho) tan(alpha)) = 0.092.
* Pivot friction (outside the library): -M_f sgn(theta') while moving; at theta' = 0 the block sticks while
  |moment of gravity and ground| <= M_f (at theta = 0 this raises the uplift thresholds by M_f / (m H)).
* Vertical table (outside the library): a_v from the horizontal input through a second-order causal
  Butterworth low-pass, then delayed; felt in the restoring moment and the uplift thresholds only.
* Sensors: *the time lag delays the theta channel of every record, free vibrations included (they show a
  hold of tau at the start); a free vibration is released at the true angle and read with the offset.

Conventions, and how they differ from the first generator
---------------------------------------------------------
* Integrator: adaptive Dormand-Prince 5(4) (FSAL, embedded error estimate, rtol 1e-9, atol 1e-11 rad and
  1e-10 rad/s), compiled with numba; steps never cross a sample boundary (the input is only piecewise
  smooth). The first generator: fixed-step RK4, 8 substeps per sample, reduced pivot coordinates.
* Ground acceleration: linear between samples by default; ``convention="held"`` holds each sample over its
  interval (zero-order hold). The first generator: linear only.
* Events (impact at theta = 0, velocity reversal under pivot friction, contact changes of the flexible
  foundation, overturn at |theta| = pi/2): the event function is evaluated on the cubic Hermite interpolant
  of the accepted step (end values and end derivatives of every state) and its root found by the Illinois
  method; one step of the integrator is then taken from the step's start to that root. Uplift from rest
  (and the end of a stick under pivot friction) is a threshold crossing of the input alone, which is affine
  in time within a sample, so it is solved exactly. The first generator: bisection on re-integrated steps.
* Rest: after an impact the block rests when |theta'| < 1e-4 rad/s (the first generator: the excursion the
  speed could reach below 1e-7 rad). It lifts off again when the input passes the thresholds above, with
  each corner's own alpha.
* Impact law: the angular momentum about the landing corner, computed from the corner vectors at theta = 0
  (:func:`momentum_ratio`); ``restitution`` and ``restitution_drift`` impose sqrt(r) instead.
* Ground motions (:func:`ground_motion`): Clough-Penzien filtered white noise (a Kanai-Tajimi filter followed
  by a second-order high-pass) under a Saragoni-Hart envelope; half the records add a
  Mavroeidis-Papageorgiou velocity pulse; scaled to a PGA of 1.0-2.5 g tan(alpha); 8 s (at 500 Hz unless
  the option ``dt`` says otherwise) of which the last 1.5 s are quiet. The first generator: a band-pass, a
  (t/t1)^2 exp envelope, sine pulses, 6 s.
* Noise: Gaussian 0.8 mrad on theta (seed section 3.4); optional Gaussian noise ``acc_noise`` [m/s^2] on
  the written ground_acc column (the block felt the clean input). The sensor options below replace the
  theta noise where they are given.
* Random numbers: numpy ``Generator`` seeded from ``SeedSequence([seed, 0x5EED2])``; record i draws from
  the child with spawn key (1, i) (free vibrations: (0, j)), so a record does not change when n grows. That
  child spawns four: the ground motion, the theta noise, the acc_noise and the sensor faults.
* Writer: time ``%.6f``, values ``%.10g``; 4000 samples per ground-motion record at 500 Hz (t = 0 .. 7.998 s).
  Free vibrations (12 s, ground_acc = 0) are released at rest from +0.75, -0.55 and +0.4 alpha (stated
  alpha; the asymmetric block, which would topple, from +0.6, -0.2, +0.4 alpha) and are recorded first,
  in the middle (after n_ground // 2 ground motions) and last. The first generator: ``%.4f``/``%.9e``,
  6 s, releases 0.8, -0.65, 0.5 alpha, all free vibrations first.

Sample rate, specimen scale, sensors (campaign options; the first generator has none of them)
----------------------------------------------------------------------------------------------
All are optional keys of a case's parameters (or of ``write_campaign(..., options=...)``); left out, a campaign
is byte-identical to one written before they existed.

* ``dt`` [s]: the sample interval of every record (default :data:`DT` = 0.002 s, 500 Hz; 0.005 and 0.001 s are
  used and tested). Ground motions and free vibrations are generated at that dt with their durations in seconds
  kept (8 s and 12 s: 1600 / 8000 samples per ground motion at 200 / 1000 Hz); the integrator (its steps end on
  the samples) and its event location are the same at every rate. The time column follows.
* ``scale`` [-]: a geometrically similar block: 2H, 2B and the depth x scale, m x scale^3, the inertia about a
  pivot x scale^5 (I0 = scale^5 m g R / p^2 of the seed specimen), so that p = P_STATED / sqrt(scale) while
  alpha and Housner's r = (1 - 2 m B^2 / I0)^2 stay the seed's. campaign.toml's [specimen] states the scaled
  height, width, depth, mass and p (the scaled block's true p). The ground motions' frequencies (Kanai-Tajimi
  ground frequency :data:`FG_RANGE` and its high-pass, pulse frequency :data:`FP_RANGE`) are multiplied by
  1 / sqrt(scale) (the same random numbers drawn), so that omega / p, and with the PGA kept at 1.0-2.5
  g tan(alpha) the block's dimensionless response, are those of the seed block's campaign (the envelope, the
  pulse's timing and the durations are not scaled).
* ``g`` [m/s^2]: the gravity of the generator's world (default standard gravity, 9.80665): the block rocks
  under it (its inertia kept, so its true p is P_STATED sqrt(g / 9.80665), which the [specimen] states, as a
  laboratory would measure it), and campaign.toml states ``g`` unless ``state_g`` is False (a campaign from
  code that does not say which g it took). The ground motions are drawn as at standard gravity.
* Sensor noise on theta (:func:`sensor_noise`; given any of these keys it replaces the white 0.8 mrad):
  ``noise_white`` [rad] white Gaussian sd (default :data:`NOISE`); ``noise_ou`` [rad] the stationary sd of an
  Ornstein-Uhlenbeck part of correlation time ``noise_tau`` [s] (exact AR(1) discretisation, started from its
  stationary distribution in every record); ``hum_amp`` [rad] and ``hum_freq`` [Hz] (default 50 Hz) a mains
  hum, a sinusoid plus its second harmonic at a third of the amplitude, phase-locked, a random phase per
  record, sampled without an anti-alias filter. Total sd sqrt(white^2 + ou^2 + hum_amp^2 / 2 (1 + 1/9))
  (:func:`noise_truth`). Drawn from the record's noise stream, so deterministic per seed.
* Sensor faults on theta (:func:`sensor_faults`, drawn from the record's fault stream): the sensor's output is
  gain_k (theta(t - tau) + offset) + noise, where ``gain_end`` [-] makes gain_k drift linearly from 1.0 at the
  first record to gain_end at the last (recording order; the noise is not scaled); then clipped to
  +-``saturation`` [rad] (the sensor's range); then the transmission adds isolated one-sample spikes of
  +-``spike_amp`` [rad] at Poisson times of rate ``spike_rate`` [1/s] (not clipped); then the logger drops out
  at Poisson times of rate ``dropout_rate`` [1/s], repeating the last value received for ``dropout_len`` [s].
  The ground_acc column is not affected.

Cases: :data:`CASES` maps a name to (the generator's own truth parameters, the expected diagnosis): a tuple
of registry effect names, or the localisation class (``housner.scenarios.diagnosis.comparison.pointers.CLASSES``,
"drift" and
"vertical_input" among them) that should come first for an effect the library does not have. :func:`library_parameters`
gives the library's parameterisation of each case the library can represent. :data:`EXAMPLE_CASES` are the
campaigns of the effects shipped as plugins in ``examples/effects`` (pivot friction with asymmetric pivots, an
accelerometer that reads 12 % high, a vertical table whose acceleration is recorded in a ``ground_acc_vertical``
column): they are not part of the diagnosis matrix. The ``colored_*`` and ``white_big_1000hz`` cases of
:data:`CASES` are Housner's physics read with the sensor options and other rates and specimens (the diagnosis
should find nothing). :data:`FAULT_CASES` (not in the matrix either) add sensor faults: name -> (truth
parameters, expected diagnosis, the faults' names (:func:`expected_faults`)); :func:`noise_truth` gives a
case's theta noise for comparison with an estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numba import njit
from scipy import signal

# ----------------------------------------------------------------------------
# specimen and measurement
G = 9.80665  # [m/s^2]
#: Seed specimen: 2H [m], 2B [m], depth [m], mass [kg], measured p [1/s].
HEIGHT, WIDTH, DEPTH, MASS, P_STATED = 0.5, 0.075, 0.4, 3.94, 4.8883
H_COM, B_HALF = HEIGHT / 2, WIDTH / 2  # centre of mass above the pivot line, half the pivot distance [m]
R_STATED = math.hypot(B_HALF, H_COM)  # [m]
ALPHA = math.atan2(B_HALF, H_COM)  # stated alpha [rad]
I0_STATED = MASS * G * R_STATED / P_STATED**2  # inertia about a pivot consistent with p [kg m^2]
#: Housner's angular-velocity ratio at impact of the stated specimen, 1 - 2 m B^2 / I0 [-] (r = its square).
RHO_STATED = 1.0 - 2.0 * MASS * B_HALF**2 / I0_STATED
R_HOUSNER = RHO_STATED**2  # 0.9465

DT = 0.002  # 500 Hz [s]
NOISE = 0.8e-3  # theta noise [rad] (seed section 3.4)
HUM_FREQ = 50.0  # mains hum of the sensor options, when hum_amp is given without hum_freq [Hz]
GM_DURATION = 8.0  # [s]
QUIET = 1.5  # quiet end of a ground-motion record [s]
FV_DURATION = 12.0  # [s]
FV_RELEASES = (0.75, -0.55, 0.4)  # release angles over the stated alpha [-]
PGA_RANGE = (1.0, 2.5)  # peak ground acceleration over g tan(alpha) [-]
FG_RANGE = (2.5, 5.0)  # Kanai-Tajimi ground frequency [Hz]
FP_RANGE = (2.0, 4.0)  # velocity-pulse frequency [Hz]
PULSE_RANGE = (0.6, 1.2)  # pulse peak acceleration over the noise's [-]
PULSE_BACKGROUND = 0.15  # with the option ``pulses``: the broadband background's peak over the pulse's [-]
REST_SPEED = 1e-4  # rest rule after an impact [rad/s]
RTOL = 1e-9
ATOL_THETA = 1e-11  # [rad]
_SEED_TAG = 0x5EED2

# ----------------------------------------------------------------------------
# cases: the generator's own parameters (SI), and what the diagnosis should say
#: name -> (truth parameters, expected). Parameter keys: r (energy ratio at impact, both impacts) [-],
#: r_exponent (amplitude-dependent restitution exponent) [-], c [1/s], e (centre of mass toward +x) [m],
#: p (true frequency parameter; r and alpha stay the stated specimen's) [1/s], offset [rad], tau [s],
#: foundation_freq [Hz] and foundation_zeta [-] (two-spring foundation), mu [-] (Coulomb friction at the
#: base), pivot_moment [N m], vertical_ratio [-], vertical_cutoff [Hz], vertical_delay [s], r_end [-]
#: (restitution drifting linearly from r to r_end along the recording order), and the campaign options
#: convention ("linear"/"held"), acc_noise [m/s^2], fv_releases (release angles over the stated alpha), dt [s],
#: scale [-], noise_white [rad], noise_ou [rad], noise_tau [s], hum_amp [rad], hum_freq [Hz], and the faults
#: saturation [rad], gain_end [-], spike_rate [1/s], spike_amp [rad], dropout_rate [1/s], dropout_len [s]
#: (module docstring, "Sample rate, specimen scale, sensors").
CASES: dict[str, tuple[dict, tuple[str, ...] | str]] = {
    "none": ({}, ()),
    "none_held": ({"convention": "held"}, ()),
    "none_acc_noise": ({"acc_noise": 0.02}, ()),
    "restitution": ({"r": 0.90}, ("restitution",)),
    "amplitude_dependent_restitution": ({"r_exponent": 0.4}, ("amplitude_dependent_restitution",)),
    "rotational_damping": ({"c": 0.8}, ("rotational_damping",)),
    # e = B/4 leaves alpha+ = 0.752 alpha: released at -0.55 alpha the block lands on its +x corner with more
    # energy than tips it over (any release beyond -0.27 alpha does), and at +0.75 alpha it sits 0.3 % below
    # its own alpha+; its free vibrations are released at +0.6, -0.2, +0.4 alpha instead (all rock)
    "asymmetric_pivots": ({"e": 0.25 * B_HALF, "fv_releases": (0.6, -0.2, 0.4)}, ("asymmetric_pivots",)),
    "frequency_parameter": ({"p": 1.06 * P_STATED}, ("frequency_parameter",)),
    "sensor_offset": ({"offset": 3.0e-3}, ("sensor_offset",)),
    "time_lag": ({"tau": 0.012}, ("time_lag",)),
    # 30 Hz vertical frequency on the two springs (the seed measured 25 Hz), 40 % damping
    "flexible_foundation": ({"foundation_freq": 30.0, "foundation_zeta": 0.4}, ("flexible_foundation",)),
    # mu < tan(alpha) = 0.15: a ground motion makes the block slide and never rock (Shenton 1996); the free
    # vibrations rock as Housner's block (friction demand <= 0.092 while rocking, impulse ratio 0.092)
    "sliding": ({"mu": 0.11}, ("sliding",)),
    "time_lag+restitution": ({"tau": 0.008, "r": 0.90}, ("restitution", "time_lag")),
    "frequency_parameter+sensor_offset": (
        {"p": 0.95 * P_STATED, "offset": 3.0e-3},
        ("frequency_parameter", "sensor_offset"),
    ),
    # outside the library
    "pivot_friction": ({"pivot_moment": 0.09}, "dissipation"),
    "vertical_table": ({"vertical_ratio": 0.25, "vertical_cutoff": 8.0, "vertical_delay": 0.03}, "vertical_input"),
    "restitution_drift": ({"r": 0.947, "r_end": 0.852}, "drift"),
    # Housner's physics read by realistic sensors and on other specimens (see "Sample rate, specimen scale,
    # sensors" in the module docstring): nothing physical to find
    "colored_tau0.02": ({"noise_white": 0.3e-3, "noise_ou": 0.8e-3, "noise_tau": 0.02}, ()),
    "colored_tau0.2": ({"noise_white": 0.3e-3, "noise_ou": 0.8e-3, "noise_tau": 0.2}, ()),
    "colored_hum50": (
        {"noise_white": 0.4e-3, "noise_ou": 0.6e-3, "noise_tau": 0.1, "hum_amp": 0.6e-3, "hum_freq": 50.0},
        (),
    ),
    "colored_hum60_big_200hz": (
        {
            "scale": 2.0,
            "dt": 0.005,
            "noise_white": 0.4e-3,
            "noise_ou": 0.8e-3,
            "noise_tau": 0.5,
            "hum_amp": 0.5e-3,
            "hum_freq": 60.0,
        },
        (),
    ),
    "white_big_1000hz": ({"scale": 1.6, "dt": 0.001, "noise_white": 0.8e-3}, ()),
    "colored_small_1000hz": (
        {
            "scale": 0.7,
            "dt": 0.001,
            "noise_white": 0.2e-3,
            "noise_ou": 0.6e-3,
            "noise_tau": 0.05,
            "hum_amp": 0.3e-3,
            "hum_freq": 50.0,
        },
        (),
    ),
}

#: Campaigns with sensor faults, kept out of :data:`CASES` (the diagnosis matrix): name -> (truth parameters,
#: expected diagnosis as in CASES, the faults present). Fault names: "saturation" (the theta channel clipped at
#: +-saturation [rad]), "gain_drift" (the theta sensor's gain drifting from 1 to gain_end [-] along the recording
#: order), "spikes" (isolated one-sample spikes of +-spike_amp [rad] at spike_rate [1/s]), "dropouts" (the logger
#: holding the last value for dropout_len [s], at dropout_rate [1/s]). A saturation of 0.45 alpha (67 mrad) clips
#: the larger ground-motion records' peaks and the starts of the free vibrations released at +0.75 and -0.55 alpha.
FAULT_CASES: dict[str, tuple[dict, tuple[str, ...], tuple[str, ...]]] = {
    "saturation": ({"saturation": 0.45 * ALPHA}, (), ("saturation",)),
    "gain_drift": ({"gain_end": 1.25}, (), ("gain_drift",)),
    "spikes_dropouts": (
        {"spike_rate": 0.3, "spike_amp": 25e-3, "dropout_rate": 0.1, "dropout_len": 0.1},
        (),
        ("spikes", "dropouts"),
    ),
    "saturation_colored_restitution": (
        {"r": 0.90, **CASES["colored_hum50"][0], "saturation": 0.45 * ALPHA},
        ("restitution",),
        ("saturation",),
    ),
}

#: Campaigns of the example effects (examples/effects, loaded as plugins), not diagnosed: name -> truth parameters.
#: acc_gain [-]: the written ground_acc is acc_gain times the acceleration the block felt; vertical_channel: the
#: vertical acceleration the block felt is written as a `ground_acc_vertical [m/s^2]` column (zeros in the free
#: vibrations). The vertical input is four times the ``vertical_table`` case's, so that its gain is well measured.
EXAMPLE_CASES: dict[str, dict] = {
    "pivot_friction+asymmetric_pivots": {"pivot_moment": 0.09, "e": 0.25 * B_HALF, "fv_releases": (0.6, -0.2, 0.4)},
    "accelerometer_gain": {"acc_gain": 1.12},
    "vertical_table_measured": {
        "vertical_ratio": 1.0,
        "vertical_cutoff": 8.0,
        "vertical_delay": 0.03,
        "vertical_channel": True,
    },
}

#: Campaign options: parameters of the recording (and the specimen's size), not of the physics' effects.
#: scale is the only one that changes the block (:func:`truth_for`); the sensor's are described in
#: :func:`sensor_noise` and :func:`sensor_faults`.
_SENSOR_KEYS = ("noise_white", "noise_ou", "noise_tau", "hum_amp", "hum_freq")
_FAULT_KEYS = ("saturation", "gain_end", "spike_rate", "spike_amp", "dropout_rate", "dropout_len")
_INPUT_KEYS = (
    "convention",
    "acc_noise",
    "fv_releases",
    "acc_gain",
    "vertical_channel",
    "dt",
    "scale",
    "g",
    "state_g",
    "tan_alpha",
    "pulses",
    *_SENSOR_KEYS,
    *_FAULT_KEYS,
)


# ----------------------------------------------------------------------------
# the truth
@dataclass(frozen=True)
class Truth:
    """The physics a campaign is generated with (SI units).

    Attributes
    ----------
    b_pos, b_neg : float
        Horizontal distance from the centre of mass to the +x and the -x pivot [m].
    i_c : float
        Centroidal moment of inertia [kg m^2].
    rho_pn, rho_np : float
        theta' after / before an impact that leaves the +x corner and lands on the -x corner, and the
        converse [-] (sqrt of the energy ratio r of that impact).
    r_exponent : float
        Amplitude-dependent restitution: the energy ratio of an impact is
        clip(rho^2 (|theta'| / (p_s alpha_s))^n, 0, 1), p_s and alpha_s of the corner before the impact [-].
    c : float
        Viscous rotational damping rate: moment -c I0 theta' [1/s].
    offset : float
        Constant offset of the theta channel [rad].
    tau : float
        Lag of the theta channel behind ground_acc [s].
    pivot_moment : float
        Coulomb moment at the pivot M_f [N m]: -M_f sgn(theta') while moving; the block sticks while the
        magnitude of the other moments stays <= M_f.
    vertical_ratio, vertical_cutoff, vertical_delay : float
        Vertical table acceleration a_v = ratio x (horizontal input low-passed by a second-order Butterworth
        at the cutoff [Hz]) delayed by the delay [s]; felt as g -> g + a_v, not recorded.
    r_end : float
        Restitution drift: the energy ratio of record k (of n_records, in recording order) is
        r + (r_end - r) k / (n_records - 1), with r = rho_pn^2 (NaN: no drift).
    n_records : int
        Number of records of the campaign (for the drift).
    mu : float
        Coulomb friction coefficient at the base [-] (inf: no sliding). Only mu < tan(alpha) is modelled.
    foundation_freq, foundation_zeta : float
        Two-spring foundation: vertical natural frequency on both springs [Hz] (inf: rigid ground) and the
        damping ratio of that mode [-]; per corner k = m (2 pi f)^2 / 2, c = zeta m 2 pi f.
    mass, height : float
        m [kg] and H, the height of the centre of mass above the pivot line [m].
    """

    b_pos: float = B_HALF
    b_neg: float = B_HALF
    i_c: float = I0_STATED - MASS * R_STATED**2
    rho_pn: float = RHO_STATED
    rho_np: float = RHO_STATED
    r_exponent: float = 0.0
    c: float = 0.0
    offset: float = 0.0
    tau: float = 0.0
    pivot_moment: float = 0.0
    vertical_ratio: float = 0.0
    vertical_cutoff: float = 8.0
    vertical_delay: float = 0.0
    r_end: float = math.nan
    n_records: int = 0
    mu: float = math.inf
    foundation_freq: float = math.inf
    foundation_zeta: float = 0.0
    mass: float = MASS
    height: float = H_COM
    g: float = G

    def side(self, s: int) -> tuple[float, float, float, float]:
        """(alpha [rad], R [m], I0 [kg m^2], p [1/s]) of the corner of side s (+1: +x)."""
        b = self.b_pos if s > 0 else self.b_neg
        rr = math.hypot(b, self.height)
        i0 = self.i_c + self.mass * rr * rr
        return math.atan2(b, self.height), rr, i0, math.sqrt(self.mass * self.g * rr / i0)

    def rho_for(self, record_index: int) -> tuple[float, float]:
        """(rho_pn, rho_np) of record ``record_index`` (recording order), with the drift if any."""
        if math.isnan(self.r_end):
            return self.rho_pn, self.rho_np
        x = record_index / max(self.n_records - 1, 1)
        r = self.rho_pn**2 + (self.r_end - self.rho_pn**2) * x
        return math.sqrt(r), math.sqrt(r)


def momentum_ratio(b_pos: float, b_neg: float, height: float, i_c: float, mass: float) -> tuple[float, float]:
    """theta' after / before an impact, from the angular momentum about the landing corner [-].

    At theta = 0 the block turns at rate w about the old corner O; the centre of mass G moves with
    v = w z x (G - O). The impulse acts at the new corner N, so L_N = I_c w + m (G - N) x v is kept and
    equals (I_c + m |G - N|^2) w' after. Returns (rho_pn, rho_np): leaving the +x corner for the -x corner,
    and the converse. Vectors are in the plane (x, z), counter-clockwise positive; only the ratio matters.
    """

    def cross(a, b):
        return a[0] * b[1] - a[1] * b[0]

    com = np.array([0.0, height])
    corner = {+1: np.array([b_pos, 0.0]), -1: np.array([-b_neg, 0.0])}
    out = []
    for old in (+1, -1):
        new = -old
        go, gn = com - corner[old], com - corner[new]
        v = np.array([-go[1], go[0]])  # z x (G - O) for w = 1
        out.append((i_c + mass * cross(gn, v)) / (i_c + mass * float(gn @ gn)))
    return out[0], out[1]


def case_parameters(case: str) -> dict:
    """The generator's own truth parameters of ``case`` (a copy of its :data:`CASES`', :data:`EXAMPLE_CASES`' or
    :data:`FAULT_CASES`' entry)."""
    if case in EXAMPLE_CASES:
        return dict(EXAMPLE_CASES[case])
    if case in FAULT_CASES:
        return dict(FAULT_CASES[case][0])
    if case in PULSE_CASES:
        return dict(PULSE_CASES[case][0])
    if case not in CASES:
        known = [*CASES, *EXAMPLE_CASES, *FAULT_CASES, *PULSE_CASES]
        raise KeyError(f"unknown case {case!r}; known: {', '.join(known)}")
    return dict(CASES[case][0])


def expected_diagnosis(case: str):
    """What the diagnosis should say of ``case`` (:data:`CASES`, :data:`FAULT_CASES`), None for an example case."""
    if case in EXAMPLE_CASES:
        return None
    if case in FAULT_CASES:
        return FAULT_CASES[case][1]
    if case in PULSE_CASES:
        return PULSE_CASES[case][1]
    return CASES[case][1]


def expected_faults(case: str) -> tuple[str, ...]:
    """The sensor faults in ``case``'s campaign (:data:`FAULT_CASES`); () for every other case."""
    case_parameters(case)  # unknown names raise
    return FAULT_CASES[case][2] if case in FAULT_CASES else ()


def sample_interval(case: str, *, options: dict | None = None) -> float:
    """The sample interval of every record of ``case`` [s] (option ``dt``, default :data:`DT` = 0.002 s)."""
    return float(campaign_options(case, options).get("dt", DT))


def stated_specimen(case: str, *, options: dict | None = None) -> dict[str, float]:
    """The [specimen] table of ``case``'s campaign.toml: height = 2H, width = 2B, depth [m], mass [kg] and p [1/s].

    With the option ``scale`` the block is the seed specimen geometrically enlarged: lengths x scale, mass x
    scale^3, the inertia about a pivot x scale^5, so p = P_STATED / sqrt(scale), the stated p being the scaled
    block's true one (alpha and Housner's r are those of the seed specimen). ``options`` overrides the case's
    options as in :func:`write_campaign`.
    """
    opts = campaign_options(case, options)
    scale = float(opts.get("scale", 1.0))
    at_g = math.sqrt(float(opts.get("g", G)) / G)  # the same block rocks with p ~ sqrt(g) where g is another
    if "tan_alpha" in opts:
        block = _block(opts)
        return {
            "height": 2 * block.height,
            "width": 2 * block.b_pos,
            "depth": DEPTH * scale,
            "mass": block.mass,
            "p": block.side(1)[3],
        }
    if scale == 1.0:
        return {"height": HEIGHT, "width": WIDTH, "depth": DEPTH, "mass": MASS, "p": P_STATED * at_g}
    return {
        "height": HEIGHT * scale,
        "width": WIDTH * scale,
        "depth": DEPTH * scale,
        "mass": MASS * scale**3,
        "p": P_STATED / math.sqrt(scale) * at_g,
    }


def noise_truth(case: str, *, options: dict | None = None) -> dict[str, float]:
    """The theta channel's noise of ``case`` (:func:`sensor_noise`), for comparison with an estimate.

    Returns a dict: ``sd`` the total standard deviation sqrt(white^2 + ou^2 + hum_amp^2 / 2 (1 + 1/9)) [rad];
    ``white`` [rad], ``ou`` [rad] (stationary sd), ``tau`` [s] (NaN without an OU part), ``hum_amp`` [rad],
    ``hum_freq`` [Hz], ``dt`` [s]; ``lag1`` the autocorrelation at one sample, (ou^2 exp(-dt/tau) + hum_amp^2 / 2
    (cos(w dt) + cos(2 w dt) / 9)) / sd^2 with w = 2 pi hum_freq [-]. ``options`` overrides the case's options
    as in :func:`write_campaign`.
    """
    kw = campaign_options(case, options)
    white = float(kw.get("noise_white", NOISE))
    ou = float(kw.get("noise_ou", 0.0))
    tau = float(kw.get("noise_tau", math.nan)) if ou > 0.0 else math.nan
    hum = float(kw.get("hum_amp", 0.0))
    f_hum = float(kw.get("hum_freq", HUM_FREQ))
    dt = float(kw.get("dt", DT))
    var_hum = 0.5 * hum**2 * (1.0 + 1.0 / 9.0)
    var = white**2 + ou**2 + var_hum
    w = 2 * math.pi * f_hum
    cov1 = (ou**2 * math.exp(-dt / tau) if ou > 0.0 else 0.0) + 0.5 * hum**2 * (
        math.cos(w * dt) + math.cos(2 * w * dt) / 9.0
    )
    return {
        "sd": math.sqrt(var),
        "white": white,
        "ou": ou,
        "tau": tau,
        "hum_amp": hum,
        "hum_freq": f_hum,
        "dt": dt,
        "lag1": cov1 / var,
    }


def _block(opts: dict) -> Truth:
    """The block of the campaign options ``opts`` before any effect: the seed specimen, enlarged by ``scale``,
    made slenderer or stockier by ``tan_alpha`` (the height kept, the pivots moved, the inertia about a pivot kept
    in its ratio to m R^2, Housner's impact from the new corners), rocking under gravity ``g``."""
    truth = Truth(g=float(opts.get("g", G)))
    scale = float(opts.get("scale", 1.0))
    if scale != 1.0:
        # lengths x scale, mass x scale^3, inertia about a pivot x scale^5: p -> p / sqrt(scale), same alpha, r
        m_s, h_s, b_s = MASS * scale**3, H_COM * scale, B_HALF * scale
        i0_s = I0_STATED * scale**5
        truth = replace(truth, b_pos=b_s, b_neg=b_s, height=h_s, mass=m_s, i_c=i0_s - m_s * math.hypot(b_s, h_s) ** 2)
    if "tan_alpha" in opts:
        h, m = truth.height, truth.mass
        rr = math.hypot(truth.b_pos, h)
        ratio = (truth.i_c + m * rr * rr) / (m * rr * rr)
        b = h * float(opts["tan_alpha"])
        rr = math.hypot(b, h)
        i_c = (ratio - 1.0) * m * rr * rr
        rho_pn, rho_np = momentum_ratio(b, b, h, i_c, m)
        truth = replace(truth, b_pos=b, b_neg=b, i_c=i_c, rho_pn=rho_pn, rho_np=rho_np)
    return truth


def truth_for(case: str, n_records: int = 0, *, options: dict | None = None) -> Truth:
    """The :class:`Truth` of ``case`` (``n_records`` sets the length of a restitution drift).

    The option ``scale`` (of the case, or in ``options`` as in :func:`write_campaign`) enlarges the seed block
    first (:func:`stated_specimen`); ``p`` and ``e`` then act on the scaled block (``e`` in metres).
    """
    kw = {k: v for k, v in case_parameters(case).items() if k not in _INPUT_KEYS}
    truth = _block(campaign_options(case, options))
    if "p" in kw:
        # the block rocks with another p than the stated one: its inertia about a pivot follows from that p,
        # its impacts keep the stated specimen's r (the mis-stated p is then the only thing wrong)
        rr = math.hypot(truth.b_pos, truth.height)
        i0 = truth.mass * truth.g * rr / kw.pop("p") ** 2
        truth = replace(truth, i_c=i0 - truth.mass * rr**2)
    if "e" in kw:
        e = kw.pop("e")
        b_pos, b_neg = truth.b_pos - e, truth.b_neg + e
        rho_pn, rho_np = momentum_ratio(b_pos, b_neg, truth.height, truth.i_c, truth.mass)
        truth = replace(truth, b_pos=b_pos, b_neg=b_neg, rho_pn=rho_pn, rho_np=rho_np)
    if "r" in kw:
        rho = math.sqrt(kw.pop("r"))
        truth = replace(truth, rho_pn=rho, rho_np=rho)
    if "r_end" in kw:
        truth = replace(truth, n_records=int(n_records))
    truth = replace(truth, **kw)
    if truth.mu < math.inf:
        tan_min = min(truth.b_pos, truth.b_neg) / truth.height
        # impulse of a Housner impact, horizontal over vertical: (1 - rho) / ((1 + rho) tan(alpha))
        impulse = max((1 - rho) / ((1 + rho) * tan_min) for rho in (truth.rho_pn, truth.rho_np))
        if not impulse < truth.mu < tan_min:
            raise NotImplementedError(
                f"sliding is modelled for {impulse:.3f} < mu < tan(alpha) = {tan_min:.3f} only (slide, never rock "
                "from rest; the pivot of a free vibration holds through its impacts)"
            )
    return truth


def library_parameters(case: str) -> dict[str, dict[str, float]]:
    """The case in the library's parameterisation: registry effect name -> its parameters (SI).

    Empty for the controls; effects outside the library are given in the generator's own terms under
    their case name, but for the example cases, which name the example effects (examples/effects).
    """
    kw = case_parameters(case)
    out: dict[str, dict[str, float]] = {}
    if case in EXAMPLE_CASES:
        if "e" in kw:
            out["asymmetric_pivots"] = {"e": kw["e"]}
        if "pivot_moment" in kw:
            out["pivot_friction"] = {"moment": kw["pivot_moment"]}
        if "acc_gain" in kw:
            out["accelerometer_gain"] = {"gain": kw["acc_gain"]}
        if kw.get("vertical_channel"):
            out["vertical_table"] = {"gain": 1.0}  # the block feels the recorded channel
        return out
    if "r" in kw and "r_end" not in kw:
        out["restitution"] = {"r": kw["r"]}
    if "r_exponent" in kw:
        out["amplitude_dependent_restitution"] = {"exponent": kw["r_exponent"]}
    if "c" in kw:
        out["rotational_damping"] = {"c": kw["c"]}
    if "e" in kw:
        out["asymmetric_pivots"] = {"e": kw["e"]}
    if "p" in kw:
        out["frequency_parameter"] = {"factor": kw["p"] / P_STATED}
    if "offset" in kw:
        out["sensor_offset"] = {"offset": kw["offset"]}
    if "tau" in kw:
        out["time_lag"] = {"tau": kw["tau"]}
    if "foundation_freq" in kw:
        out["flexible_foundation"] = {"frequency": kw["foundation_freq"], "damping_ratio": kw["foundation_zeta"]}
    if "mu" in kw:
        out["sliding"] = {"mu": kw["mu"]}
    if not isinstance(expected_diagnosis(case), tuple):
        out[case] = {k: v for k, v in kw.items() if k not in _INPUT_KEYS}
    return out


# ----------------------------------------------------------------------------
# the integrator (numba)
# Constants vector q (SI): the block, then per-side geometry (precomputed: the right-hand side is called
# ~10^6 times per campaign), the impact law, the foundation.
(
    Q_M,
    Q_G,
    Q_H,
    Q_BP,
    Q_BN,
    Q_IC,
    Q_C,
    Q_MF,
    Q_MU,
    Q_KAPPA,
    Q_ETA,
    Q_RP,
    Q_RN,
    Q_AP,
    Q_AN,
    Q_I0P,
    Q_I0N,
    Q_RHO_PN,
    Q_RHO_NP,
    Q_REXP,
    Q_REST,
) = range(21)
N_Q = 21
#: Model kinds and the rigid block's modes.
RIGID, FLEX = 0, 1
REST, ROCK, STICK, OVER = 0, 1, 2, 3
#: Mode vector md: pivot side s, direction of motion sig (pivot friction), +x and -x corner on its spring.
M_S, M_SIG, M_AP, M_AN = range(4)
#: Input vector gin over the current sample, local time t in [0, dt]: ug'' = a0 + a1 t, a_v = v0 + v1 t.
#: Dormand-Prince 5(4) tableau.
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1 / 5, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3 / 40, 9 / 40, 0.0, 0.0, 0.0, 0.0],
        [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0, 0.0],
        [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0, 0.0],
        [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0.0],
        [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
    ]
)
#: 5th-order weights minus the embedded 4th-order ones (the error estimate).
_E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])
#: At most this many events in one sample before the kernel gives up (chattering contact).
_MAX_EVENTS = 400
#: Status codes of the kernels.
OK, OVERTURNED, ERR_FRICTION, ERR_CHATTER = 0, 1, -1, -2


@njit(cache=True)
def _rigid_moment(th, a, geff, s, q):
    """Moment about pivot s of gravity (g + a_v) and the ground's inertia force [N m] (no losses)."""
    if s > 0:
        rr, al = q[Q_RP], q[Q_AP]
    else:
        rr, al = q[Q_RN], q[Q_AN]
    d = s * al - th
    return -q[Q_M] * rr * (geff * math.sin(d) + a * math.cos(d))


@njit(cache=True)
def _deriv(kind, t, y, dy, q, md, gin):
    """dy/dt of the state y at local time t [s] (rigid: theta, theta'; flexible: theta, theta', w, w')."""
    a = gin[0] + gin[1] * t
    geff = q[Q_G] + gin[2] + gin[3] * t
    s = md[M_S]
    i0 = q[Q_I0P] if s > 0 else q[Q_I0N]
    th, thd = y[0], y[1]
    if kind == RIGID:
        mom = _rigid_moment(th, a, geff, s, q) - q[Q_C] * i0 * thd - q[Q_MF] * md[M_SIG]
        dy[0] = thd
        dy[1] = mom / i0
        return
    # Two-spring foundation, per unit mass; derived with Lagrange's equations in (theta, w), the pivot corner
    # held horizontally (see _flex_forces for the springs). x_G - x_pivot = -s b_s cos + H sin, so
    # ax = dx_G/dtheta = s b_s sin + H cos; z_G = w + H cos.
    w, wd = y[2], y[3]
    sn, cs = math.sin(th), math.cos(th)
    hh = q[Q_H]
    sb = q[Q_BP] if s > 0 else -q[Q_BN]
    ax = sb * sn + hh * cs
    ax_th = sb * cs - hh * sn
    fp, fn = _flex_forces(th, thd, w, wd, md[M_AP] > 0.5, md[M_AN] > 0.5, q)
    m = q[Q_M]
    num = (
        -ax * (a + ax_th * thd * thd)
        + hh * sn * (fp + fn)
        - cs * (q[Q_BP] * fp - q[Q_BN] * fn)
        - q[Q_C] * (i0 / m) * thd
    )
    thdd = num / (q[Q_IC] / m + ax * ax)
    dy[0] = thd
    dy[1] = thdd
    dy[2] = wd
    dy[3] = -geff + fp + fn + hh * (sn * thdd + cs * thd * thd)


@njit(cache=True)
def _flex_gaps(th, thd, w, wd, q):
    """Penetrations d [m] and their rates [m/s] of the +x and -x corner (z_corner = w -+ b sin(theta))."""
    sn, cs = math.sin(th), math.cos(th)
    dp = q[Q_BP] * sn - w
    dn = -q[Q_BN] * sn - w
    return dp, q[Q_BP] * cs * thd - wd, dn, -q[Q_BN] * cs * thd - wd


@njit(cache=True)
def _flex_forces(th, thd, w, wd, ap, an, q):
    """Spring-dashpot forces per unit mass [m/s^2] of the corners on their springs (frozen mode: may pull)."""
    dp, dpd, dn, dnd = _flex_gaps(th, thd, w, wd, q)
    fp = q[Q_KAPPA] * dp + q[Q_ETA] * dpd if ap else 0.0
    fn = q[Q_KAPPA] * dn + q[Q_ETA] * dnd if an else 0.0
    return fp, fn


@njit(cache=True)
def _flex_push(th, thd, w, wd, q):
    """Contact functions of the two corners: > 0 exactly when the corner is pressed in and pushes."""
    dp, dpd, dn, dnd = _flex_gaps(th, thd, w, wd, q)
    return min(dp, q[Q_KAPPA] * dp + q[Q_ETA] * dpd), min(dn, q[Q_KAPPA] * dn + q[Q_ETA] * dnd)


@njit(cache=True)
def _margins(kind, y, q, md, out):
    """Event functions of the frozen mode; each is >= 0 while the mode holds and turns negative at its event.

    0: s theta (impact, or the pivot switch of the foundation); 1: pi/2 - |theta| (overturn); rigid 2:
    sig theta' (velocity reversal, pivot friction only); flexible 2, 3: the +x and -x contact functions,
    with the sign of the corner's state (on its spring: must keep pushing; off: must not push).
    """
    out[0] = md[M_S] * y[0]
    out[1] = 0.5 * math.pi - abs(y[0])
    if kind == RIGID:
        out[2] = md[M_SIG] * y[1] if q[Q_MF] > 0.0 else 1.0
        out[3] = 1.0
        return
    gp, gn = _flex_push(y[0], y[1], y[2], y[3], q)
    out[2] = gp if md[M_AP] > 0.5 else -gp
    out[3] = gn if md[M_AN] > 0.5 else -gn


@njit(cache=True)
def _dp5(kind, t, y, f0, h, q, md, gin, k, ytmp, ynew, atol):
    """One Dormand-Prince 5(4) step of length h from (t, y) with f0 = y'(t).

    Writes the 5th-order solution to ``ynew`` and its derivative (FSAL) to ``k[6]``; returns the error
    norm (RMS of the embedded error over atol + rtol max(|y|, |ynew|); <= 1 accepts the step).
    """
    n = y.size
    k[0, :] = f0
    for i in range(1, 7):
        for j in range(n):
            acc = 0.0
            for l in range(i):
                acc += _A[i, l] * k[l, j]
            ytmp[j] = y[j] + h * acc
        _deriv(kind, t + _C[i] * h, ytmp, k[i], q, md, gin)
        if i == 6:
            ynew[:] = ytmp  # row 6 of the tableau is the 5th-order solution
    err = 0.0
    for j in range(n):
        e = 0.0
        for l in range(7):
            e += _E[l] * k[l, j]
        sc = atol[j] + RTOL * max(abs(y[j]), abs(ynew[j]))
        err += (h * e / sc) ** 2
    return math.sqrt(err / n)


@njit(cache=True)
def _hermite(u, h, y0, f0, y1, f1, out):
    """Cubic Hermite interpolant of a step of length h at the fraction u in [0, 1] (dense output)."""
    u2 = u * u
    u3 = u2 * u
    h00 = 2 * u3 - 3 * u2 + 1
    h10 = u3 - 2 * u2 + u
    h01 = -2 * u3 + 3 * u2
    h11 = u3 - u2
    for j in range(y0.size):
        out[j] = h00 * y0[j] + h10 * h * f0[j] + h01 * y1[j] + h11 * h * f1[j]


@njit(cache=True)
def _locate(kind, idx, g_lo, g_hi, h, y0, f0, y1, f1, q, md, yi, gv):
    """Root u in [0, 1] of event function ``idx`` on the dense output, by the Illinois method.

    g_lo and g_hi < 0 are its values at the step's ends; returns the first root's fraction of the step
    (to ~1e-14 of the step). A step that starts on the event surface (g_lo = 0: just after an impact, a
    pivot switch or a velocity reversal, the state moving off it) may come back within the step (a bounce):
    the bracket then starts at the largest u = 2^-j where the interpolant is positive, found by halving
    toward 0; when there is none the mode is violated at once (returns 0). g_lo < 0 returns 0.
    """
    ul, gl, ur, gr = 0.0, g_lo, 1.0, g_hi
    if g_lo < 0.0:
        return 0.0
    if g_lo == 0.0:
        u = 1.0
        for _ in range(60):
            u *= 0.5
            _hermite(u, h, y0, f0, y1, f1, yi)
            _margins(kind, yi, q, md, gv)
            if gv[idx] > 0.0:
                ul, gl = u, gv[idx]
                break
            if gv[idx] < 0.0:
                ur, gr = u, gv[idx]
        if gl <= 0.0:
            return 0.0
    side = 0
    for _ in range(100):
        if ur - ul < 1e-14:
            break
        u = (ul * gr - ur * gl) / (gr - gl)
        if not ul < u < ur:
            u = 0.5 * (ul + ur)
        _hermite(u, h, y0, f0, y1, f1, yi)
        _margins(kind, yi, q, md, gv)
        g = gv[idx]
        if g == 0.0:
            return u
        if g < 0.0:
            ur, gr = u, g
            if side == -1:
                gl *= 0.5  # Illinois: halve the stale end's value so the bracket shrinks from both sides
            side = -1
        else:
            ul, gl = u, g
            if side == 1:
                gr *= 0.5
            side = 1
    return 0.5 * (ul + ur)


@njit(cache=True)
def _affine_leave(f_beg, f_end, span):
    """First local time in [0, span] where an affine function going f_beg -> f_end turns positive (-1: none)."""
    if f_beg > 0.0:
        return 0.0
    if f_end > 0.0:
        return span * (-f_beg) / (f_end - f_beg)
    return -1.0


@njit(cache=True)
def _at_rest_leave(th, s, gin, tau, dt, q, sliding):
    """How a block stuck at theta (rest at 0, or held by pivot friction) starts to move in [tau, dt].

    Returns (local time, pivot side, direction of motion); time -1 when it stays put through the sample.
    At theta = 0 it lifts onto the +x corner once the moment about that corner, -m (g + a_v) b+ - m ug'' H,
    exceeds M_f, and onto the -x corner once minus the moment about it, m ug'' H - m (g + a_v) b-, does
    (tan(alpha+-) = b+- / H: each corner its own threshold). Held at theta != 0 by pivot friction, it moves
    either way once the moment's magnitude exceeds M_f. The moment is affine in time within a sample, so
    the crossing is solved exactly. A sliding block (mu < tan(alpha)) never lifts from rest: friction caps
    the horizontal force on its base at mu m g < m g tan(alpha) (Shenton 1996).
    """
    if sliding:
        return -1.0, s, 0.0
    t_best, s_best, sig_best = -1.0, s, 0.0
    for c in range(2):
        if th == 0.0:
            side = 1.0 if c == 0 else -1.0
            sig = side  # from theta = 0 the block can only turn onto the corner it lifts on
        else:
            side = s
            sig = 1.0 if c == 0 else -1.0
        f = np.empty(2)
        for j in range(2):
            tt = tau if j == 0 else dt
            mom = _rigid_moment(th, gin[0] + gin[1] * tt, q[Q_G] + gin[2] + gin[3] * tt, side, q)
            f[j] = sig * mom - q[Q_MF]
        t_go = _affine_leave(f[0], f[1], dt - tau)
        if t_go >= 0.0 and (t_best < 0.0 or tau + t_go < t_best):
            t_best, s_best, sig_best = tau + t_go, side, sig
    return t_best, s_best, sig_best


@njit(cache=True)
def _friction_demand(y, dy, a, geff, s, q):
    """Horizontal over vertical base force of a rocking block whose pivot holds [-] (sliding check)."""
    if s > 0:
        rr, al = q[Q_RP], q[Q_AP]
    else:
        rr, al = q[Q_RN], q[Q_AN]
    d = s * al - y[0]
    # centre of mass relative to the pivot: R (-sin d, cos d), d' = -theta'
    fx = a + rr * (dy[1] * math.cos(d) + y[1] * y[1] * math.sin(d))
    fz = geff + rr * (dy[1] * math.sin(d) - y[1] * y[1] * math.cos(d))
    return abs(fx) / fz if fz > 0.0 else math.inf


@njit(cache=True)
def _run(kind, acc, av, dt, held, q, y_init, out, imp):
    """Integrate one record; theta at every sample goes to ``out``.

    Parameters
    ----------
    kind : int
        RIGID or FLEX.
    acc, av : float64[:]
        Horizontal ground and vertical table acceleration at the samples [m/s^2].
    dt : float
        Sample step [s].
    held : bool
        Zero-order hold of the input (else linear between samples).
    q : float64[:]
        Constants (layout Q_*).
    y_init : float64[:]
        Initial state (theta [rad], theta' [rad/s][, w [m], w' [m/s]]).
    out : float64[:]
        theta at the samples [rad].
    imp : float64[:, 3]
        Impact log: time [s], theta' before and after [rad/s] (rigid block; filled up to its size).

    Returns
    -------
    (status, n_impacts)
    """
    n = acc.size
    nst = y_init.size
    y = y_init.copy()
    f0 = np.empty(nst)
    ynew = np.empty(nst)
    ytmp = np.empty(nst)
    yev = np.empty(nst)
    k = np.empty((7, nst))
    gv0 = np.empty(4)
    gv1 = np.empty(4)
    gvi = np.empty(4)
    atol = np.empty(nst)
    atol[0], atol[1] = ATOL_THETA, 10 * ATOL_THETA
    if nst == 4:
        atol[2], atol[3] = 1e-12, 1e-10  # w [m], w' [m/s]: ~1e-6 of the static deflection
    md = np.zeros(4)
    gin = np.zeros(4)
    sliding = q[Q_MU] < math.inf
    th = y[0]
    md[M_S] = 1.0 if (th > 0.0 or (th == 0.0 and y[1] >= 0.0)) else -1.0
    mode = ROCK
    n_imp = 0
    if kind == FLEX:
        gp, gn = _flex_push(y[0], y[1], y[2], y[3], q)
        md[M_AP] = 1.0 if gp > 0.0 else 0.0
        md[M_AN] = 1.0 if gn > 0.0 else 0.0
    elif y[0] == 0.0 and y[1] == 0.0:
        mode = REST
    elif y[1] == 0.0:
        # released at rest from a tilt: it moves (toward rest) unless pivot friction holds it
        gin[0], gin[2] = acc[0], av[0]
        mom = _rigid_moment(y[0], acc[0], q[Q_G] + av[0], md[M_S], q)
        if abs(mom) <= q[Q_MF]:
            mode = STICK
        md[M_SIG] = 1.0 if mom > 0.0 else -1.0
    else:
        md[M_SIG] = 1.0 if y[1] > 0.0 else -1.0
    out[0] = y[0]
    h = 0.25 * dt
    status = OK
    for ks in range(n - 1):
        if mode == OVER:
            out[ks + 1] = y[0]
            continue
        gin[0] = acc[ks]
        gin[2] = av[ks]
        if held:
            gin[1], gin[3] = 0.0, 0.0
        else:
            gin[1] = (acc[ks + 1] - acc[ks]) / dt
            gin[3] = (av[ks + 1] - av[ks]) / dt
        tau = 0.0
        n_ev = 0
        fresh = True  # f0 must be (re)computed: new input, or a state changed by an event
        while dt - tau > 1e-12 * dt and mode != OVER:
            if mode == REST or mode == STICK:
                t_go, s_new, sig = _at_rest_leave(y[0], md[M_S], gin, tau, dt, q, sliding)
                if t_go < 0.0:
                    break
                tau = t_go
                md[M_S], md[M_SIG] = s_new, sig
                y[1] = 0.0
                mode = ROCK
                fresh = True
                if dt - tau <= 1e-12 * dt:
                    break
            if fresh:
                _deriv(kind, tau, y, f0, q, md, gin)
                fresh = False
            hs = min(h, dt - tau)
            if dt - tau - hs < 1e-3 * hs:
                hs = dt - tau  # no sliver of a step before the sample boundary
            err = _dp5(kind, tau, y, f0, hs, q, md, gin, k, ytmp, ynew, atol)
            if not err <= 1.0:  # also NaN
                h = hs * max(0.2, 0.9 * err**-0.2) if err == err else 0.1 * hs
                continue
            grow = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err**-0.2))
            # events of the frozen mode: the earliest root of an event function that ends the step negative
            _margins(kind, y, q, md, gv0)
            _margins(kind, ynew, q, md, gv1)
            u_ev, i_ev = 2.0, -1
            for i in range(4):
                if gv1[i] < 0.0:
                    u = _locate(kind, i, gv0[i], gv1[i], hs, y, f0, ynew, k[6], q, md, ytmp, gvi)
                    if u < u_ev:
                        u_ev, i_ev = u, i
            if i_ev < 0:
                tau += hs
                y[:] = ynew
                f0[:] = k[6]
                # a step cut short by the sample boundary says nothing against the proposal in force
                h = hs * grow if hs >= h else max(h, hs * grow)
                if sliding and mode == ROCK:
                    a = gin[0] + gin[1] * tau
                    if _friction_demand(y, f0, a, q[Q_G] + gin[2] + gin[3] * tau, md[M_S], q) > q[Q_MU]:
                        status = ERR_FRICTION
                        mode = OVER
                continue
            # step to the event: one integrator step from the step's start to the root on the dense output
            he = u_ev * hs
            if he > 0.0:
                _dp5(kind, tau, y, f0, he, q, md, gin, k, ytmp, yev, atol)
                y[:] = yev
            tau += he
            fresh = True
            n_ev += 1
            if n_ev > _MAX_EVENTS:
                status = ERR_CHATTER
                mode = OVER
                break
            if i_ev == 1:  # overturned: the block lies on its side
                y[0] = md[M_S] * 0.5 * math.pi
                mode = OVER
                status = OVERTURNED
                break
            if kind == FLEX:
                if i_ev == 0:
                    y[0] = 0.0  # the pivot switches sides (continuous: at theta = 0 the corners move vertically)
                    md[M_S] = -md[M_S]
                elif i_ev == 2:
                    md[M_AP] = 1.0 - md[M_AP]
                else:
                    md[M_AN] = 1.0 - md[M_AN]
                continue
            if i_ev == 0:  # impact: the other corner lands
                s = md[M_S]
                rho = q[Q_RHO_PN] if s > 0 else q[Q_RHO_NP]
                if q[Q_REXP] != 0.0:
                    i0s = q[Q_I0P] if s > 0 else q[Q_I0N]
                    p_s = math.sqrt(q[Q_M] * q[Q_G] * (q[Q_RP] if s > 0 else q[Q_RN]) / i0s)
                    ref = p_s * (q[Q_AP] if s > 0 else q[Q_AN])
                    r_eff = min(1.0, max(0.0, rho * rho * (abs(y[1]) / ref) ** q[Q_REXP]))
                    rho = math.sqrt(r_eff)
                w_before = y[1]
                y[0] = 0.0
                y[1] = rho * w_before
                md[M_S] = -s
                if n_imp < imp.shape[0]:
                    imp[n_imp, 0] = ks * dt + tau
                    imp[n_imp, 1] = w_before
                    imp[n_imp, 2] = y[1]
                n_imp += 1
                if abs(y[1]) < q[Q_REST]:
                    y[1] = 0.0
                    mode = REST
                else:
                    md[M_SIG] = 1.0 if y[1] > 0.0 else -1.0
                continue
            # i_ev == 2: theta' reverses under pivot friction: it sticks, or moves the other way
            y[1] = 0.0
            a = gin[0] + gin[1] * tau
            mom = _rigid_moment(y[0], a, q[Q_G] + gin[2] + gin[3] * tau, md[M_S], q)
            if abs(mom) <= q[Q_MF]:
                mode = STICK if y[0] != 0.0 else REST
            else:
                md[M_SIG] = 1.0 if mom > 0.0 else -1.0
        if mode == OVER and status == OVERTURNED:
            out[ks + 1] = y[0]
            continue
        if status < 0:
            return status, n_imp
        out[ks + 1] = y[0]
    return status, n_imp


def _constants(truth: Truth, rho: tuple[float, float]) -> np.ndarray:
    q = np.zeros(N_Q)
    q[Q_M], q[Q_G], q[Q_H], q[Q_BP], q[Q_BN], q[Q_IC] = (
        truth.mass,
        truth.g,
        truth.height,
        truth.b_pos,
        truth.b_neg,
        truth.i_c,
    )
    q[Q_C], q[Q_MF], q[Q_MU] = truth.c, truth.pivot_moment, truth.mu
    if math.isfinite(truth.foundation_freq):
        omega = 2 * math.pi * truth.foundation_freq
        q[Q_KAPPA] = 0.5 * omega**2  # k / m per corner: both springs together give omega^2
        q[Q_ETA] = truth.foundation_zeta * omega  # c / m per corner: 2 c / m = 2 zeta omega
    for side, (ia, ir, ii) in ((1, (Q_AP, Q_RP, Q_I0P)), (-1, (Q_AN, Q_RN, Q_I0N))):
        al, rr, i0, _p = truth.side(side)
        q[ia], q[ir], q[ii] = al, rr, i0
    q[Q_RHO_PN], q[Q_RHO_NP] = rho
    q[Q_REXP] = truth.r_exponent
    q[Q_REST] = REST_SPEED
    return q


def vertical_input(truth: Truth, acc: np.ndarray, dt: float) -> np.ndarray:
    """The vertical table acceleration a_v [m/s^2] the block feels with ``acc`` [m/s^2] (0 without the effect).

    a_v = ratio x (acc through a causal second-order Butterworth low-pass at the cutoff), delayed by the delay
    (linear interpolation between samples, 0 before the record starts).
    """
    if truth.vertical_ratio == 0.0:
        return np.zeros(acc.size)
    b, a = signal.butter(2, truth.vertical_cutoff, fs=1.0 / dt)
    lp = signal.lfilter(b, a, acc)
    k = np.arange(acc.size, dtype=float)
    return truth.vertical_ratio * np.interp(k - truth.vertical_delay / dt, k, lp, left=0.0)


def simulate_details(
    truth: Truth,
    acc: np.ndarray,
    dt: float,
    *,
    theta0: float = 0.0,
    record_index: int = 0,
    convention: str = "linear",
    max_impacts: int = 4096,
) -> tuple[np.ndarray, bool, np.ndarray]:
    """:func:`simulate`, also returning the impact log (time [s], theta' before, after [rad/s]) of a rigid block."""
    if convention not in ("linear", "held"):
        raise ValueError(f"convention must be 'linear' or 'held', got {convention!r}")
    acc = np.ascontiguousarray(acc, dtype=np.float64)
    q = _constants(truth, truth.rho_for(record_index))
    av = vertical_input(truth, acc, dt)
    out = np.empty(acc.size)
    imp = np.full((max_impacts, 3), np.nan)
    if math.isfinite(truth.foundation_freq):
        kind = FLEX
        # released at rest with its weight on the springs: both corners at theta = 0 (they share it when the
        # block is symmetric), else the lower corner alone carrying m g
        g_k = G / q[Q_KAPPA]  # penetration of one spring under the whole weight [m]
        if theta0 == 0.0:
            if truth.b_pos != truth.b_neg:
                raise NotImplementedError("the foundation starts level only for a symmetric block")
            w0 = -0.5 * g_k
        elif theta0 > 0.0:
            w0 = truth.b_pos * math.sin(theta0) - g_k
        else:
            w0 = -truth.b_neg * math.sin(theta0) - g_k
        y0 = np.array([float(theta0), 0.0, w0, 0.0])
    else:
        kind = RIGID
        y0 = np.array([float(theta0), 0.0])
    status, n_imp = _run(kind, acc, av, float(dt), convention == "held", q, y0, out, imp)
    if status == ERR_FRICTION:
        raise NotImplementedError("the pivot of a rocking block would slip (slide-rock is not modelled)")
    if status == ERR_CHATTER:
        raise RuntimeError(f"more than {_MAX_EVENTS} events in one sample (chattering contact)")
    return out, status == OVERTURNED, imp[: min(n_imp, max_impacts)]


def simulate(
    truth: Truth, acc: np.ndarray, dt: float, *, theta0: float = 0.0, record_index: int = 0, convention: str = "linear"
) -> tuple[np.ndarray, bool]:
    """The block's rotation at the samples of a ground motion.

    Parameters
    ----------
    truth : Truth
        The physics.
    acc : array_like
        Horizontal ground acceleration at the samples [m/s^2] (linear between them, or held).
    dt : float
        Sample step [s].
    theta0 : float
        Initial rotation [rad]; the block starts at rest (theta' = 0).
    record_index : int
        Position of the record in the recording order (restitution drift).
    convention : {"linear", "held"}
        Input between samples.

    Returns
    -------
    theta : ndarray
        Rotation at the samples [rad], the block's own (no sensor effects); +-pi/2 once overturned.
    overturned : bool
    """
    theta, over, _imp = simulate_details(
        truth, acc, dt, theta0=theta0, record_index=record_index, convention=convention
    )
    return theta, over


# ----------------------------------------------------------------------------
# ground motions
def _mp_pulse_acc(t: np.ndarray, fp: float, gamma: float, nu: float, t0: float) -> np.ndarray:
    """Acceleration of a Mavroeidis-Papageorgiou velocity pulse of unit amplitude (its exact derivative) [1/s].

    v(t) = 1/2 (1 + cos(2 pi fp tau / gamma)) cos(2 pi fp tau + nu), |tau| = |t - t0| <= gamma / (2 fp).
    """
    om = 2 * math.pi * fp
    tau = t - t0
    inside = np.abs(tau) <= gamma / (2 * fp)
    env = 0.5 * (1 + np.cos(om * tau / gamma))
    denv = -0.5 * (om / gamma) * np.sin(om * tau / gamma)
    a = denv * np.cos(om * tau + nu) - env * om * np.sin(om * tau + nu)
    return np.where(inside, a, 0.0)


def ground_motion(
    rng: np.random.Generator,
    *,
    dt: float = DT,
    duration: float = GM_DURATION,
    freq_scale: float = 1.0,
    tan_alpha: float | None = None,
    pulses: bool = False,
) -> np.ndarray:
    """One synthetic ground motion at model scale [m/s^2], ``duration`` s at ``dt`` (n = duration / dt samples).

    ``freq_scale`` [-] multiplies the drawn ground and pulse frequencies (the same random numbers are drawn):
    a block enlarged by ``scale`` gets 1 / sqrt(scale), so that it responds as the seed block does.

    Clough-Penzien: white noise through a Kanai-Tajimi filter (ground frequency :data:`FG_RANGE`, 2.5-5 Hz,
    damping 0.3-0.6) and a second-order high-pass (a tenth of the ground frequency, the same damping),
    discretised by a zero-order hold of the continuous system; under a Saragoni-Hart envelope
    (t/tp)^b exp(b (1 - t/tp)) with peak time tp 0.8-2 s and shape b 1.5-3. Half the records add a
    Mavroeidis-Papageorgiou velocity pulse (frequency :data:`FP_RANGE`, 2-4 Hz; gamma 1.5-3; phase nu
    uniform; centre 1.5-3.5 s) with :data:`PULSE_RANGE` (0.6-1.2) times the noise's peak acceleration. The
    shaking (duration - 1.5 s) ends with a 0.3 s cosine taper, the last 1.5 s are quiet; the peak is scaled
    to :data:`PGA_RANGE` (1.0-2.5) g tan(alpha) of the stated specimen (uniform).

    The ranges were chosen so that Housner's seed block overturns under a fifth to a third of the records
    (lower ground and pulse frequencies, 1.5-4 and 1-2.5 Hz, made 40-45 % overturn): 22-32 % for seeds
    0-5 of a 60-record campaign (seed 0: 19 of 60, median theta_max/alpha 0.36 of the others).

    ``tan_alpha``: the block's, for the PGA (default the stated specimen's). ``pulses``: a near-fault record,
    every one a pulse (the same draws) over a weak broadband background, :data:`PULSE_BACKGROUND` of its peak.
    """
    n = int(round(duration / dt))
    n_shake = int(round((duration - QUIET) / dt))
    t = np.arange(n_shake) * dt
    fg = rng.uniform(*FG_RANGE) * freq_scale
    zg = rng.uniform(0.3, 0.6)
    wg, wf = 2 * math.pi * fg, 2 * math.pi * 0.1 * fg
    num = np.polymul([2 * zg * wg, wg * wg], [1.0, 0.0, 0.0])
    den = np.polymul([1.0, 2 * zg * wg, wg * wg], [1.0, 2 * zg * wf, wf * wf])
    bd, ad, _dt = signal.cont2discrete((num, den), dt, method="zoh")
    x = signal.lfilter(np.ravel(bd), ad, rng.standard_normal(n_shake))
    tp = rng.uniform(0.8, 2.0)
    bb = rng.uniform(1.5, 3.0)
    x = x * (t / tp) ** bb * np.exp(bb * (1 - t / tp))
    x /= np.max(np.abs(x))
    if rng.random() < 0.5 or pulses:
        pulse = _mp_pulse_acc(
            t,
            rng.uniform(*FP_RANGE) * freq_scale,
            rng.uniform(1.5, 3.0),
            rng.uniform(0, 2 * math.pi),
            rng.uniform(1.5, 3.5),
        )
        share = rng.uniform(*PULSE_RANGE)
        x = (
            PULSE_BACKGROUND * x + pulse / np.max(np.abs(pulse))
            if pulses
            else x + share * pulse / np.max(np.abs(pulse))
        )
    k = int(round(0.3 / dt))
    x[-k:] *= 0.5 * (1 + np.cos(np.linspace(0.0, math.pi, k)))
    out = np.zeros(n)
    ta = math.tan(ALPHA) if tan_alpha is None else tan_alpha
    out[:n_shake] = x / np.max(np.abs(x)) * rng.uniform(*PGA_RANGE) * G * ta
    return out


# ----------------------------------------------------------------------------
# campaigns
def sensor_noise(
    rng: np.random.Generator,
    n: int,
    dt: float,
    *,
    white: float = NOISE,
    ou: float = 0.0,
    tau: float = math.nan,
    hum_amp: float = 0.0,
    hum_freq: float = HUM_FREQ,
) -> np.ndarray:
    """The theta channel's noise over one record of ``n`` samples at ``dt`` [s] (zero mean) [rad].

    The sum of: white Gaussian noise of sd ``white`` [rad]; an Ornstein-Uhlenbeck process of stationary sd ``ou``
    [rad] and correlation time ``tau`` [s], discretised exactly (AR(1): x_k+1 = a x_k + ou sqrt(1 - a^2) e_k,
    a = exp(-dt / tau)) and started from its stationary distribution (x_0 ~ N(0, ou^2)); a mains hum
    hum_amp (sin(phi_k) + sin(2 phi_k) / 3), phi_k = 2 pi hum_freq k dt + phi, its phase phi uniform per record
    and the second harmonic locked to it (a distorted mains waveform), sampled as it is (no anti-alias filter: at
    200 Hz a 120 Hz harmonic appears at 80 Hz). Drawn in that order from ``rng``: n normals, n normals when ou > 0,
    one uniform when hum_amp > 0 (with the defaults this is the first generator's ``rng.normal(0, NOISE, n)``).
    Total sd sqrt(white^2 + ou^2 + hum_amp^2 / 2 (1 + 1/9)) (:func:`noise_truth`).
    """
    x = rng.normal(0.0, white, n)
    if ou > 0.0:
        if not tau > 0.0:
            raise ValueError(f"an Ornstein-Uhlenbeck part needs a correlation time noise_tau > 0 s, got {tau!r}")
        a = math.exp(-dt / tau)
        e = rng.standard_normal(n)
        e[0] *= ou
        e[1:] *= ou * math.sqrt(-math.expm1(-2.0 * dt / tau))  # ou sqrt(1 - a^2), without cancellation
        x = x + signal.lfilter([1.0], [1.0, -a], e)
    if hum_amp > 0.0:
        phase = 2 * math.pi * hum_freq * dt * np.arange(n) + rng.uniform(0.0, 2 * math.pi)
        x = x + hum_amp * (np.sin(phase) + np.sin(2.0 * phase) / 3.0)
    return x


def sensor_faults(
    x: np.ndarray,
    dt: float,
    rng: np.random.Generator,
    *,
    saturation: float = math.inf,
    spike_rate: float = 0.0,
    spike_amp: float = 0.0,
    dropout_rate: float = 0.0,
    dropout_len: float = 0.0,
) -> tuple[np.ndarray, dict]:
    """The written theta channel: the sensor's output ``x`` [rad] (signal, gain and noise) through the faults.

    In this order: the sensor's range clips x to +-``saturation`` [rad]; the transmission adds isolated
    one-sample spikes of +-``spike_amp`` [rad] (sign uniform) at the times of a Poisson process of rate
    ``spike_rate`` [1/s] (a spike on a sample next to an earlier one is dropped, so all are isolated; the
    spikes are not clipped); the logger drops out at the times of a Poisson process of rate ``dropout_rate``
    [1/s] (a start on sample 0 moves to sample 1), repeating the last value it received (the sample before
    the start) for round(``dropout_len`` / dt) samples, cut at the record's end (a later dropout may extend an
    earlier one; a held run may hide a spike). Poisson counts over the record's duration n dt, times uniform
    (drawn from ``rng``: spikes' count, times, signs, then dropouts' count, times).

    Returns
    -------
    (written, log)
        log: ``clipped`` (number of clipped samples), ``spikes`` (sample indices), ``dropouts`` ((start,
        length) per run, in samples).
    """
    y = np.clip(x, -saturation, saturation) if math.isfinite(saturation) else x.copy()
    n = y.size
    clipped = int(np.count_nonzero(np.abs(x) > saturation)) if math.isfinite(saturation) else 0
    spikes: list[int] = []
    if spike_rate > 0.0:
        count = rng.poisson(spike_rate * n * dt)
        idx = np.sort(np.floor(rng.uniform(0.0, n, count)).astype(np.int64))
        sign = rng.choice(np.array([-1.0, 1.0]), count)
        last = -2
        for i, sg in zip(idx, sign, strict=True):
            if i <= last + 1:
                continue
            y[i] += sg * spike_amp
            spikes.append(int(i))
            last = i
    dropouts: list[tuple[int, int]] = []
    if dropout_rate > 0.0:
        count = rng.poisson(dropout_rate * n * dt)
        starts = np.sort(np.maximum(np.floor(rng.uniform(0.0, n, count)).astype(np.int64), 1))
        length = max(1, int(round(dropout_len / dt)))
        for i in starts:
            j = min(int(i) + length, n)
            y[i:j] = y[i - 1]
            dropouts.append((int(i), j - int(i)))
    return y, {"clipped": clipped, "spikes": spikes, "dropouts": dropouts}


def _observe(
    truth: Truth,
    theta: np.ndarray,
    dt: float,
    rng: np.random.Generator,
    *,
    gain: float = 1.0,
    noise: dict | None = None,
) -> np.ndarray:
    """What the theta sensor puts out: gain x (theta(t - tau) (held at the start) + the offset), plus the noise
    (:func:`sensor_noise` with ``noise``' keyword arguments; default white :data:`NOISE`)."""
    th = theta
    if truth.tau != 0.0:
        k = np.arange(th.size, dtype=float)
        th = np.interp(k - truth.tau / dt, k, th)  # np.interp holds the end values outside the record
    if noise is None and gain == 1.0:
        return th + truth.offset + rng.normal(0.0, NOISE, th.size)
    signal_out = th + truth.offset
    if gain != 1.0:
        signal_out = gain * signal_out
    return signal_out + sensor_noise(rng, th.size, dt, **(noise or {}))


def _write_csv(path: Path, acc: np.ndarray, theta: np.ndarray, dt: float, vertical: np.ndarray | None = None) -> None:
    t = np.arange(acc.size) * dt
    cols, fmt, header = [t, acc, theta], ["%.6f", "%.10g", "%.10g"], "time,ground_acc,theta"
    if vertical is not None:
        cols.append(vertical)
        fmt.append("%.10g")
        header += ",ground_acc_vertical [m/s^2]"
    np.savetxt(path, np.column_stack(cols), fmt=fmt, delimiter=",", header=header, comments="")


def recording_order(n_ground: int) -> list[tuple[str, str, int]]:
    """(id, kind, index among its kind) in recording order: fv01, the first half of the ground motions, fv02,
    the second half, fv03."""
    gm = [(f"gm{i + 1:03d}", "ground_motion", i) for i in range(n_ground)]
    fv = [(f"fv{j + 1:02d}", "free_vibration", j) for j in range(len(FV_RELEASES))]
    half = n_ground // 2
    return [fv[0], *gm[:half], fv[1], *gm[half:], *fv[2:]]


def _seed(seed: int, kind: int, i: int) -> np.random.SeedSequence:
    # the i-th child of the kind's branch: SeedSequence(entropy).spawn(...)[kind].spawn(...)[i]
    return np.random.SeedSequence([seed, _SEED_TAG], spawn_key=(kind, i))


def campaign_options(case: str, options: dict | None = None) -> dict:
    """The campaign options of ``case`` (its :data:`_INPUT_KEYS` entries) updated with ``options``."""
    extra = set(options or {}) - set(_INPUT_KEYS)
    if extra:
        raise KeyError(f"not campaign options: {sorted(extra)}; known: {', '.join(_INPUT_KEYS)}")
    kw = {k: v for k, v in case_parameters(case).items() if k in _INPUT_KEYS}
    kw.update(options or {})
    return kw


def _toml_number(x: float) -> str:
    return repr(float(round(x, 12)))  # 0.12, not 0.12000000000000001; 1.0, not the integer 1


def write_campaign(
    root: str | Path,
    case: str = "none",
    *,
    n_ground: int = 60,
    seed: int = 0,
    convention: str | None = None,
    acc_noise: float | None = None,
    options: dict | None = None,
) -> dict:
    """Write the synthetic campaign of ``case`` to ``root`` and return what it holds.

    Parameters
    ----------
    root : path
        Directory to create (campaign.toml and records/).
    case : str
        Key of :data:`CASES`, :data:`EXAMPLE_CASES` or :data:`FAULT_CASES`.
    n_ground : int
        Number of ground-motion records.
    seed : int
        Seed of the ground motions and the noise (record i: the i-th child of a SeedSequence).
    convention : {"linear", "held"}, optional
        Input between samples as the block feels it; default the case's ("linear" but for ``none_held``).
    acc_noise : float, optional
        Standard deviation of Gaussian noise on the written ground_acc column [m/s^2]; default the case's.
    options : dict, optional
        Campaign options (keys of :data:`_INPUT_KEYS`: dt, scale, the sensor's noise and faults, ...) that
        replace the case's.

    Returns
    -------
    dict
        ``root``, ``case``, ``expected`` (None for an example case), ``faults`` (:func:`expected_faults`),
        ``truth``, ``dt`` [s], ``specimen`` (the stated [specimen] table), ``overturned`` (bool array per
        ground-motion record), ``gm_ids``, ``theta_max`` (the block's largest sampled |theta| per ground-motion
        record [rad]), ``sensor`` (record id -> the theta sensor's gain and the log of :func:`sensor_faults`,
        for the records with a fault option only).
    """
    root = Path(root)
    (root / "records").mkdir(parents=True, exist_ok=True)
    kw = campaign_options(case, options)
    convention = kw.get("convention", "linear") if convention is None else convention
    acc_noise = float(kw.get("acc_noise", 0.0) if acc_noise is None else acc_noise)
    dt = float(kw.get("dt", DT))
    scale = float(kw.get("scale", 1.0))
    freq_scale = 1.0 / math.sqrt(scale) if scale != 1.0 else 1.0
    noise = None
    if any(k in kw for k in _SENSOR_KEYS):
        nt = noise_truth(case, options=options)
        noise = {
            "white": nt["white"],
            "ou": nt["ou"],
            "tau": nt["tau"],
            "hum_amp": nt["hum_amp"],
            "hum_freq": nt["hum_freq"],
        }
    faults = {
        k: float(kw[k]) for k in ("saturation", "spike_rate", "spike_amp", "dropout_rate", "dropout_len") if k in kw
    }
    gain_end = float(kw.get("gain_end", 1.0))
    order = recording_order(n_ground)
    truth = truth_for(case, n_records=len(order), options=options)
    spec = stated_specimen(case, options=options)
    overturned, gm_ids, theta_max, sensor_log = [], [], [], {}
    if scale == 1.0 and "tan_alpha" not in kw:
        lines = [
            f'name = "independent synthetic campaign, case: {case}"',
            "[specimen]",
            f"height = {HEIGHT}",
            f"width = {WIDTH}",
            f"depth = {DEPTH}",
            f"mass = {MASS}",
            f"p = {P_STATED}" if spec["p"] == P_STATED else f"p = {_toml_number(spec['p'])}",
        ]
    else:
        lines = [
            f'name = "independent synthetic campaign, case: {case}"',
            "[specimen]",
            *(f"{k} = {_toml_number(v)}" for k, v in spec.items()),
        ]
    if "g" in kw and kw.get("state_g", True):  # the local gravity, stated before [specimen]
        lines.insert(1, f"g = {_toml_number(kw['g'])}")
    for k, (rid, kind, i) in enumerate(order):
        ss = _seed(seed, 1 if kind == "ground_motion" else 0, i)
        # the first three children are those of the first generator's ss.spawn(3); the fourth draws the faults
        motion_ss, noise_ss, acc_noise_ss, fault_ss = ss.spawn(4)
        if kind == "ground_motion":
            acc = ground_motion(
                np.random.default_rng(motion_ss),
                dt=dt,
                freq_scale=freq_scale,
                tan_alpha=kw.get("tan_alpha"),
                pulses=bool(kw.get("pulses", False)),
            )
            theta0 = 0.0
        else:
            acc = np.zeros(int(round(FV_DURATION / dt)))
            # over the stated alpha (the block's own where ``tan_alpha`` makes another block)
            theta0 = kw.get("fv_releases", FV_RELEASES)[i] * math.atan(float(kw.get("tan_alpha", math.tan(ALPHA))))
        theta, over = simulate(truth, acc, dt, theta0=theta0, record_index=k, convention=convention)
        written = acc * kw.get("acc_gain", 1.0)  # the table's accelerometer reads the gain times what was felt
        if acc_noise > 0.0 and kind == "ground_motion":
            written = written + np.random.default_rng(acc_noise_ss).normal(0.0, acc_noise, acc.size)
        vertical = vertical_input(truth, acc, dt) if kw.get("vertical_channel") else None
        gain = 1.0 + (gain_end - 1.0) * k / max(len(order) - 1, 1) if gain_end != 1.0 else 1.0
        theta_w = _observe(truth, theta, dt, np.random.default_rng(noise_ss), gain=gain, noise=noise)
        if faults or gain_end != 1.0:
            theta_w, log = sensor_faults(theta_w, dt, np.random.default_rng(fault_ss), **faults)
            sensor_log[rid] = {"gain": gain, **log}
        _write_csv(root / "records" / f"{rid}.csv", written, theta_w, dt, vertical)
        lines += ["[[record]]", f'id = "{rid}"', f'kind = "{kind}"', f'file = "records/{rid}.csv"']
        if kind == "ground_motion":
            overturned.append(over)
            gm_ids.append(rid)
            theta_max.append(float(np.max(np.abs(theta))))
    (root / "campaign.toml").write_text("\n".join(lines) + "\n")
    return {
        "root": root,
        "case": case,
        "expected": expected_diagnosis(case),
        "faults": expected_faults(case),
        "truth": truth,
        "dt": dt,
        "specimen": spec,
        "overturned": np.array(overturned, dtype=bool),
        "gm_ids": gm_ids,
        "theta_max": np.array(theta_max),
        "sensor": sensor_log,
    }


def cached_campaign(base: str | Path, case: str, *, n_ground: int = 60, seed: int = 0) -> dict:
    """:func:`write_campaign` into ``base/indep-<case>-<n_ground>-<seed>``, reused once it has a ``.complete``
    marker (tests share one campaign per session through a common base folder)."""
    root = Path(base) / f"indep-{case}-{n_ground}-{seed}"
    done = root / ".complete"
    if done.exists():
        n_rec = len(recording_order(n_ground))
        return {
            "root": root,
            "case": case,
            "expected": expected_diagnosis(case),
            "faults": expected_faults(case),
            "truth": truth_for(case, n_rec),
            "dt": sample_interval(case),
            "specimen": stated_specimen(case),
        }
    info = write_campaign(root, case, n_ground=n_ground, seed=seed)
    done.write_text("ok\n")
    return info


# ----------------------------------------------------------------------------
# near-fault pulses on a slender block (issue 51's fifth family, reproduced here)
#: A slender block (2H = 1.0 m, tan(alpha) = 0.10) under pulse records sampled at 1000 Hz, white theta noise
#: 0.5 mrad: the conditions of the campaigns of issue 51 that other code wrote.
SLENDER_PULSES = {"scale": 2.0, "tan_alpha": 0.10, "pulses": True, "dt": 0.001, "noise_white": 5e-4}
#: name -> (the generator's parameters, the expected diagnosis), as :data:`CASES`; not in the default matrix
#: (each campaign is 1000 Hz). ``g`` 9.81 without ``state_g``: a campaign written at another g that does not say
#: so (the project's reading is then 0.035 % off in a_g / g).
PULSE_CASES: dict[str, tuple[dict, tuple[str, ...] | str]] = {
    "pulse_none": (dict(SLENDER_PULSES), ()),
    "pulse_none_g981": ({**SLENDER_PULSES, "g": 9.81, "state_g": False}, ()),
    "pulse_none_g981_stated": ({**SLENDER_PULSES, "g": 9.81}, ()),
    "pulse_time_lag+frequency_parameter": (
        {**SLENDER_PULSES, "tau": 0.012, "p": 1.06 * _block(SLENDER_PULSES).side(1)[3]},
        ("frequency_parameter", "time_lag"),
    ),
    "pulse_rotational_damping": ({"pulses": True, "c": 0.45}, ("rotational_damping",)),
}
