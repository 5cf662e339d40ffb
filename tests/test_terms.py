"""Mechanics as composable terms of the analytic kernel, extra measured channels, and the shipped example effects.

The term kernel (:mod:`housner.effects.terms`) is checked three ways: without terms and with the library's
fast-path effects written as terms it must give what the plain kernel gives (bit for bit is what we get; the
brief asks 1e-12), against closed forms (work-energy with a Coulomb moment, the raised and the vertical
uplift thresholds), and against the independent generator (``tests/independent_campaigns.py``, written apart
from the library) for pivot friction combined with asymmetric pivots and with damping. The examples in
``examples/effects`` are loaded as plugins and fitted on campaigns that generator wrote with their physics.
"""

from __future__ import annotations

import hashlib
import math
import pickle
import re
from dataclasses import replace
from pathlib import Path

import independent_campaigns as ic
import numpy as np
import pytest

from housner import G, GroundMotion, Specimen, _kernel
from housner.effects import (
    EFFECTS,
    CoulombTerm,
    ImpactTerm,
    MomentTerm,
    TermSet,
    apply_effects,
    load_plugin,
    make_effect,
    simulate_with_effects,
)
from housner.effects.codegen import kernel_dir, kernel_module
from housner.effects.parameters import damping_moment, restitution_law
from housner.model import simulate
from housner.rocking_params import RockingParams
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis.comparison.history_error import error_window, scored_error
from housner.scenarios.diagnosis.comparison.record_comparison import simulate_records
from housner.scenarios.diagnosis.selection.fitting import fit_effect

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples" / "effects"
SPEC = Specimen.bachmann2017()
ALPHA = SPEC.alpha
DT = ic.DT


@pytest.fixture(scope="module")
def plugins():
    """The three example effects, registered for this module only (other tests enumerate the registry)."""
    before = dict(EFFECTS)
    names = {f: load_plugin(EXAMPLES / f"{f}.py") for f in ("pivot_friction", "accelerometer_gain", "vertical_table")}
    yield names
    EFFECTS.clear()
    EFFECTS.update(before)


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return tmp_path_factory.getbasetemp() / "independent"


def gm(seed: int) -> GroundMotion:
    """A ground motion of the independent generator (8 s at 500 Hz, 1.0-2.5 g tan(alpha))."""
    return GroundMotion(ic.ground_motion(np.random.default_rng(seed)), DT, name=f"indep-{seed}")


# ----------------------------------------------------------------------------
# without terms, and the fast-path effects as terms: the plain kernel's results
def test_the_template_without_terms_is_the_plain_kernel():
    """The kernel generated from the template (housner._kernel_steps, housner._kernel) with no term computes bit
    for bit what the plain kernel computes."""
    prm = RockingParams(ALPHA * 0.9, ALPHA * 1.1, 4.7, 5.1, 0.93, r_amp_exponent=0.2, damping=0.1, r_pos=0.95)
    motions = [gm(s) for s in (1, 2, 3)] + [GroundMotion.free_vibration(-0.6 * ALPHA, 6.0)]
    n_rec = len(motions)
    acc_g = np.concatenate([m.acc for m in motions]) / G
    off = np.zeros(n_rec + 1, np.int64)
    np.cumsum([m.n for m in motions], out=off[1:])
    args = (np.full(n_rec, DT), np.full(n_rec, 2, np.int64), np.tile(prm.as_array(), (n_rec, 1)))
    th0 = np.array([m.theta0 for m in motions])
    runs = []
    for kern in (_kernel.run_batch, kernel_module(()).run_batch):
        theta, thd = np.empty(off[-1]), np.empty(off[-1])
        imp_off = np.arange(n_rec + 1, dtype=np.int64) * 4000
        imp, out = np.zeros(imp_off[-1]), np.empty((n_rec, 6))
        kern(
            acc_g,
            np.zeros_like(acc_g),
            off,
            *args,
            np.zeros((n_rec, 0)),
            th0,
            np.zeros(n_rec),
            1e-6,
            True,
            theta,
            thd,
            imp,
            imp_off,
            out,
        )
        runs.append((theta, thd, imp, out))
    assert runs[0][3][:, 4].sum() > 50  # the records rock
    for a, b in zip(*runs, strict=True):
        assert np.array_equal(a, b, equal_nan=True)


FAST_PATH_CASES = {
    "damping": [("rotational_damping", {"c": 0.4})],
    "restitution": [("restitution", {"r": 0.9})],
    "asymmetric+restitution+amplitude": [
        ("asymmetric_pivots", {"e": 0.004}),
        ("restitution", {"r": 0.9}),
        ("amplitude_dependent_restitution", {"exponent": 0.3}),
    ],
    "amplitude+restitution+damping": [
        ("amplitude_dependent_restitution", {"exponent": -0.2}),
        ("restitution", {"r": 0.92}),
        ("rotational_damping", {"c": 0.2}),
    ],
}


@pytest.mark.parametrize("case", list(FAST_PATH_CASES))
def test_fast_path_effects_as_terms_give_the_same_response(case):
    """rotational_damping as a moment term, restitution and its amplitude dependence as impact terms: the same
    responses as their parameter-vector fast path (the default route). The arithmetic is the same operation
    for operation, so the histories are equal bit for bit; 1e-12 alpha is the brief's bound."""
    fx = [make_effect(n, **p) for n, p in FAST_PATH_CASES[case]]
    for mo in [gm(11), gm(12), GroundMotion.free_vibration(0.7 * ALPHA, 10.0)]:
        fast = simulate_with_effects(SPEC, mo, fx)
        terms = simulate_with_effects(SPEC, mo, fx, prefer_terms=True)
        assert "terms" in terms.info and "terms" not in fast.info
        assert fast.n_impacts > 5
        assert np.max(np.abs(fast.theta - terms.theta)) <= 1e-12 * ALPHA
        np.testing.assert_allclose(terms.impact_times, fast.impact_times, rtol=0, atol=1e-12)
        assert terms.theta_max == pytest.approx(fast.theta_max, rel=1e-12, abs=0)
        assert np.array_equal(fast.theta, terms.theta)  # what the kernel achieves


def test_term_sets_order_and_describe():
    law = ImpactTerm(restitution_law, (0.9, 0.8), replaces=True)
    scale = ImpactTerm(restitution_law, (0.5, 0.5))
    damp = MomentTerm(damping_moment, (0.3,), at_rest=False)
    ts = TermSet((scale, damp, law))
    assert ts.terms == (law, damp, scale)  # a law that replaces the ratio runs first
    assert ts.q_array().tolist() == [0.9, 0.8, 0.3, 0.5, 0.5]
    assert [d["term"] for d in ts.describe()] == ["impact", "moment", "impact"]
    assert ts == TermSet((scale, damp, law)) and hash(ts) == hash(TermSet((scale, damp, law)))


def test_term_functions_are_checked():
    from numba import njit

    with pytest.raises(ValueError, match="numba @njit function"):
        MomentTerm(lambda phi, w, t, a, v, s, alpha, p2, q: 0.0)
    with pytest.raises(ValueError, match="must take 8 arguments, it takes 9"):
        CoulombTerm(damping_moment)

    @njit
    def local(phi, w, t, a, v, s, alpha, p2, q):
        return 0.0

    with pytest.raises(ValueError, match="top level of an importable module"):
        MomentTerm(local)
    with pytest.raises(ValueError, match="finite numbers"):
        MomentTerm(damping_moment, (math.nan,))


def test_generated_kernels_are_written_once_and_cached_by_numba():
    """One generated file per structure, imported once per process; numba's cache index sits beside it, so a
    new process loads the machine code instead of compiling (bench_terms.py measures it: ~0.5 s vs ~8 s)."""
    mo = GroundMotion.free_vibration(0.5 * ALPHA, 2.0)
    fx = [make_effect("rotational_damping", c=0.4)]
    res = simulate_with_effects(SPEC, mo, fx, prefer_terms=True)
    structure = apply_effects(SPEC, mo, fx, prefer_terms=True).terms.structure
    mod = kernel_module(structure)
    assert kernel_module(structure) is mod and res.rocked
    path = Path(mod.__file__)
    assert path.parent == kernel_dir() and path.read_text().startswith("# Generated by housner.effects.codegen")
    stem = path.stem
    assert list((path.parent / "__pycache__").glob(f"{stem}.run_batch-*.nbi"))


# ----------------------------------------------------------------------------
# extra channels
def test_ground_motion_channels():
    acc = np.sin(np.arange(100) * 0.1)
    vert = 0.5 * np.cos(np.arange(100) * 0.1)
    plain = GroundMotion(acc, 0.01, name="m")
    mo = GroundMotion(acc, 0.01, name="m", channels={"ground_acc_vertical": vert})
    # a motion without channels hashes as before channels existed (cached results hold)
    h = hashlib.sha256(acc.tobytes() + np.array([0.01, 0.0, 0.0]).tobytes()).hexdigest()
    assert plain.content_hash() == h and mo.content_hash() != h
    other = GroundMotion(acc, 0.01, name="m", channels={"ground_acc_vertical": vert * 1.001})
    assert other.content_hash() != mo.content_hash()
    sc = mo.scaled(amplitude=2.0, time=0.5)
    assert np.array_equal(sc.channels["ground_acc_vertical"], 2.0 * vert) and sc.dt == 0.005
    longer, shorter = mo.with_duration(1.5), mo.with_duration(0.5)
    assert longer.channels["ground_acc_vertical"][:100].tolist() == vert.tolist()
    assert np.all(longer.channels["ground_acc_vertical"][100:] == 0.0)
    assert shorter.channels["ground_acc_vertical"].size == shorter.n == 51
    part = mo.sliced(10, 30)
    assert part.n == 20 and np.array_equal(part.channels["ground_acc_vertical"], vert[10:30])
    assert np.array_equal(replace(mo, acc=acc * 2).channels["ground_acc_vertical"], vert)
    back = pickle.loads(pickle.dumps(mo))
    assert back.content_hash() == mo.content_hash()
    with pytest.raises(TypeError, match="cannot be changed"):
        mo.channels["ground_acc_vertical"] = vert
    with pytest.raises(ValueError, match="one sample per sample of `acc`"):
        GroundMotion(acc, 0.01, name="m", channels={"ground_acc_vertical": vert[:50]})
    with pytest.raises(ValueError, match="named 'ground_acc_<what>'"):
        GroundMotion(acc, 0.01, name="m", channels={"vertical": vert})
    with pytest.raises(ValueError, match="not finite at sample 3"):
        GroundMotion(acc, 0.01, name="m", channels={"ground_acc_vertical": np.where(np.arange(100) == 3, np.inf, 0)})


def test_campaign_reads_extra_channels(tmp_path):
    info = ic.write_campaign(tmp_path / "c", "vertical_table_measured", n_ground=2, seed=3)
    camp = load_campaign(info["root"])
    rec = camp.record("gm001")
    raw = np.loadtxt(rec.file, delimiter=",", skiprows=1)
    assert np.array_equal(rec.motion.channels["ground_acc_vertical"], raw[:, 3])
    assert np.all(camp.record("fv01").motion.channels["ground_acc_vertical"] == 0.0)
    # a channel in another unit is converted once, like ground_acc
    text = rec.file.read_text().splitlines()
    rows = [",".join([*r.split(",")[:3], repr(float(r.split(",")[3]) / G)]) for r in text[1:]]
    rec.file.write_text("\n".join(["time,ground_acc,theta,ground_acc_vertical [g]", *rows]) + "\n")
    again = load_campaign(info["root"]).record("gm001")
    np.testing.assert_allclose(again.motion.channels["ground_acc_vertical"], raw[:, 3], rtol=1e-14, atol=1e-15)


def test_a_missing_channel_is_refused_by_name_before_any_simulation(plugins, monkeypatch):
    from housner.engines.analytic import HousnerEngine

    with_v = GroundMotion(np.zeros(50), DT, name="gm000", channels={"ground_acc_vertical": np.zeros(50)})
    without = GroundMotion(np.zeros(50), DT, name="gm001")
    fx = [make_effect("vertical_table")]
    msg = "effect 'vertical_table' reads the channel 'ground_acc_vertical', which motion 'gm001' does not carry"
    with pytest.raises(ValueError, match=re.escape(msg)):
        simulate_with_effects(SPEC, without, fx)
    calls = []
    monkeypatch.setattr("housner.engines.analytic.simulate_batch", lambda *a, **k: calls.append(1))
    with pytest.raises(ValueError, match=re.escape(msg)):
        HousnerEngine().simulate_many(SPEC, [with_v, without], fx, errors="return")
    assert calls == []


# ----------------------------------------------------------------------------
# plugins and engines
def test_load_plugin_errors(tmp_path, plugins):
    assert plugins["pivot_friction"] == ("pivot_friction",)
    with pytest.raises(ValueError, match=r"^effect plugin '.*nowhere\.py': no such file$"):
        load_plugin(tmp_path / "nowhere.py")
    empty = tmp_path / "nothing_here.py"
    empty.write_text("X = 1\n")
    with pytest.raises(ValueError, match=r"nothing_here\.py' registers no effect"):
        load_plugin(empty)
    (tmp_path / "notes.txt").write_text("")
    with pytest.raises(ValueError, match=r"notes\.txt': not a Python file"):
        load_plugin(tmp_path / "notes.txt")
    # loading the same file again re-registers the same effect
    assert load_plugin(EXAMPLES / "pivot_friction.py") == ("pivot_friction",)


def test_examples_are_short_and_documented():
    for f in ("pivot_friction", "accelerometer_gain", "vertical_table"):
        text = (EXAMPLES / f"{f}.py").read_text()
        assert len(text.splitlines()) <= 40 and text.startswith('"""')


def test_the_analytic_engine_realises_term_effects_and_others_refuse_them(plugins):
    from housner.engines.analytic import HousnerEngine
    from housner.engines.base import engine_class

    fx = [make_effect("pivot_friction", moment=0.05)]
    assert "pivot_friction" in HousnerEngine.effects_supported
    assert HousnerEngine().simulate(SPEC, GroundMotion.free_vibration(0.5 * ALPHA, 1.0), fx).rocked
    for name in ("mujoco", "pybullet", "dart", "opensees", "drake"):  # the shipped engines (tests may register others)
        try:
            cls = engine_class(name)
        except ImportError:
            continue

        class Probe(cls):
            def __init__(self):  # no model is built: the refusal comes first
                pass

        with pytest.raises(ValueError, match=f"engine '{name}' cannot realise effect 'pivot_friction'"):
            Probe().simulate(SPEC, GroundMotion.free_vibration(0.5 * ALPHA, 0.1), fx)


def test_a_mechanics_effect_takes_no_terms(plugins):
    fx = [make_effect("sliding", mu=0.3), make_effect("pivot_friction", moment=0.05)]
    with pytest.raises(
        ValueError,
        match="'sliding' replaces the equation of motion and cannot take the kernel terms of 'pivot_friction'",
    ):
        apply_effects(SPEC, GroundMotion.free_vibration(0.5 * ALPHA, 0.1), fx)


# ----------------------------------------------------------------------------
# closed forms
def test_pivot_friction_work_energy_and_stick(plugins):
    """Released at theta0 with a Coulomb moment M_f, the first impact speed obeys
    I0 w^2 / 2 = m g R (cos(alpha - theta0) - cos(alpha)) - M_f theta0; released where the restoring moment
    m g R sin(alpha - theta0) is below M_f the block stays put."""
    mf = 0.09
    fx = [make_effect("pivot_friction", moment=mf)]
    theta0 = 0.6 * ALPHA
    res = simulate_with_effects(SPEC, GroundMotion.free_vibration(theta0, 1.0, dt=1e-3), fx, substeps=8)
    work = SPEC.mass * G * SPEC.R * (math.cos(ALPHA - theta0) - math.cos(ALPHA)) - mf * theta0
    k = int(res.impact_times[0] / 1e-3)  # the last sample before the impact: extrapolate the energy to it
    th, thd = res.theta[k], res.theta_dot[k]
    energy = 0.5 * SPEC.inertia * thd**2 + SPEC.mass * G * SPEC.R * (math.cos(ALPHA - th) - math.cos(ALPHA))
    assert energy == pytest.approx(work + mf * th, rel=1e-9)  # the work-energy balance holds along the way
    stuck = ALPHA - 0.5 * math.asin(mf / (SPEC.mass * G * SPEC.R))  # restoring moment M_f / 2 there
    held = simulate_with_effects(SPEC, GroundMotion.free_vibration(stuck, 1.0), fx)
    assert np.all(held.theta == stuck) and held.n_impacts == 0
    # a free vibration ends stuck off-centre or at rest, never rocking forever
    free = simulate_with_effects(SPEC, GroundMotion.free_vibration(theta0, 8.0), fx)
    assert np.all(free.theta[-500:] == free.theta[-1])


def ramp_uplift(level: float, dt: float = DT) -> tuple[GroundMotion, float]:
    """A slow ramp of ug'' to -level g (2 s), and the time [s] at which it passes -threshold g, threshold < level."""
    t = np.arange(1001) * dt
    return GroundMotion(-level * G * np.minimum(t / 1.0, 1.0), dt, name="ramp"), 1.0 / level


def test_pivot_friction_raises_the_uplift_threshold(plugins):
    """At rest the block lifts once the moment of gravity and ground exceeds M_f:
    ug'' < -g (tan(alpha) + M_f / (m g R cos(alpha)))."""
    mf = 0.09
    thr = math.tan(ALPHA) + mf / (SPEC.mass * G * SPEC.R * math.cos(ALPHA))
    mo, t_frac = ramp_uplift(1.2 * thr)
    res = simulate_with_effects(SPEC, mo, [make_effect("pivot_friction", moment=mf)])
    # ug'' = -1.2 thr g t/1 s passes -thr g at t = 1 / 1.2 s; the root of an affine margin, to rounding
    assert res.uplift_time == pytest.approx(t_frac * thr, rel=1e-12)
    assert simulate(SPEC, mo).uplift_time == pytest.approx(t_frac * math.tan(ALPHA), rel=1e-12)


def test_vertical_table_changes_the_uplift_threshold(plugins):
    """With the table accelerating up or down at a_v the block lifts at ug'' < -g tan(alpha) (1 + a_v/g)."""
    for v in (-0.2, 0.3):
        mo, t_frac = ramp_uplift(1.5 * math.tan(ALPHA))
        mo = replace(mo, channels={"ground_acc_vertical": np.full(mo.n, v * G)})
        res = simulate_with_effects(SPEC, mo, [make_effect("vertical_table", gain=1.0)])
        assert res.uplift_time == pytest.approx(t_frac * math.tan(ALPHA) * (1 + v), rel=1e-12)


def test_terms_keep_the_mirror_symmetry(plugins):
    """ug -> -ug gives theta -> -theta bit for bit with a Coulomb and a vertical term (v is not mirrored)."""
    mo = gm(21)
    av = ic.vertical_input(ic.truth_for("vertical_table_measured"), mo.acc, DT)
    mo = replace(mo, channels={"ground_acc_vertical": av})
    fx = [make_effect("pivot_friction", moment=0.05), make_effect("vertical_table")]
    a = simulate_with_effects(SPEC, mo, fx)
    b = simulate_with_effects(SPEC, replace(mo, acc=-mo.acc), fx)
    assert a.n_impacts > 5 and np.array_equal(a.theta, -b.theta)


# ----------------------------------------------------------------------------
# composition, against the independent generator
#: Free vibrations: the two solvers differ only in their rest rules. The library stops a block whose next
#: peak would stay below rest_tol alpha = 1e-6 alpha; the generator one slower than 1e-4 rad/s, whose peak is
#: (1e-4)^2 / (2 p^2) = 2e-10 rad. So the last bounce one of them keeps is below ~1e-6 alpha (measured 1.3e-6).
FV_TOL = 5e-6
#: Ground motions: besides the rest rules (a chatter sequence cut at another instant), rocking is chaotic, so
#: a record's agreement is bounded by its conditioning, measured as the library's own change at 4x the
#: substeps (delta4): ten times that, plus ten times the rest-rule floor.
GM_FLOOR = 1e-5


@pytest.mark.parametrize("combo", ["asymmetric_pivots", "rotational_damping", "rotational_damping_term"])
def test_pivot_friction_composes_with_other_mechanics(plugins, combo):
    """Pivot friction (a Coulomb term) with asymmetric pivots (parameters: alpha, p and the impact ratios per
    corner) or with viscous damping (through the parameters, or as a second term of the same kernel) against
    the independent generator, which integrates
    I0_s theta'' = -m g R_s sin(s alpha_s - theta) - m ug'' R_s cos(...) - c I0_s theta' - M_f sgn(theta') with
    its own integrator and events: free vibrations and ground motions, record by record."""
    mf = 0.09
    by_terms = combo.endswith("_term")
    if combo == "asymmetric_pivots":
        truth = ic.truth_for("pivot_friction+asymmetric_pivots")
        fx = [make_effect("asymmetric_pivots", e=0.25 * ic.B_HALF), make_effect("pivot_friction", moment=mf)]
        releases = ic.EXAMPLE_CASES["pivot_friction+asymmetric_pivots"]["fv_releases"]
    else:
        truth = replace(ic.truth_for("pivot_friction"), c=0.8)
        fx = [make_effect("rotational_damping", c=0.8), make_effect("pivot_friction", moment=mf)]
        releases = ic.FV_RELEASES
    for x in releases:
        mine, _ = ic.simulate(truth, np.zeros(int(round(8.0 / DT)) + 1), DT, theta0=x * ALPHA)
        lib = simulate_with_effects(SPEC, GroundMotion.free_vibration(x * ALPHA, 8.0), fx, prefer_terms=by_terms)
        assert lib.n_impacts > 20 and len(lib.info["terms"]) == 1 + by_terms
        assert np.max(np.abs(lib.theta - mine)) < FV_TOL * ALPHA
    rocked = 0
    for seed in range(200, 206):
        mo = gm(seed)
        mine, over = ic.simulate(truth, mo.acc, DT)
        lib = simulate_with_effects(SPEC, mo, fx, prefer_terms=by_terms)
        fine = simulate_with_effects(SPEC, mo, fx, substeps=4 * lib.info["substeps"], prefer_terms=by_terms)
        delta4 = np.max(np.abs(lib.theta - fine.theta)) / ALPHA
        assert lib.overturned == over
        assert np.max(np.abs(lib.theta - mine)) / ALPHA < 10 * (delta4 + GM_FLOOR)
        rocked += lib.theta_max_over_alpha > 0.1
    assert rocked >= 2


# ----------------------------------------------------------------------------
# the examples fitted on campaigns written with their physics
def _objective(camp, ids):
    """Per-record time-history errors [alpha] (campaigns.history_error.scored_error, the diagnosis' measure) of
    an effect on the records ``ids``, whole records (the channels travel with them), and their noise [alpha]."""
    recs = [camp.record(i) for i in ids]
    ends = [error_window(r, ALPHA) for r in recs]

    def errors(effect):
        res = simulate_records(camp.specimen, recs, "housner", [effect])
        return np.array(
            [
                1.0 if isinstance(r, str) else scored_error(r.theta, rec, end, ALPHA)
                for r, rec, end in zip(res, recs, ends, strict=True)
            ]
        )

    return errors, np.array([r.noise / ALPHA for r in recs])


#: example -> (campaign case, n_ground, parameter, truth, tolerance). Each fit lands within 1e-4 relative of the
#: truth on seed 0 (M_f 0.089994 N m, gain 1.119999, vertical gain 1.0000); the tolerances leave room for other
#: noise draws but not for a wrong answer: on these records a change of M_f by 1 %, of the accelerometer gain by
#: 0.5 % or of the vertical gain by 5 % raises the mean error by 0.31-0.35, 3.4-4.0 and 0.96-1.6 noise sigmas
#: (measured), while the noise moves the minimum of a mean over ~10^4 samples by a few hundredths of a sigma.
FITS = {
    "pivot_friction": ("pivot_friction", 4, "moment", 0.09, 0.01),
    "accelerometer_gain": ("accelerometer_gain", 6, "gain", 1.12, 0.005),
    "vertical_table": ("vertical_table_measured", 6, "gain", 1.0, 0.05),
}


@pytest.mark.parametrize("example", list(FITS))
def test_example_fitted_on_its_campaign(plugins, base, example):
    """Fit the example's parameter (campaigns.fitting.fit_effect: grid, zoom, Brent) on its independent
    campaign: it recovers the truth, and the error falls to the sensor noise (pivot friction: on the free
    vibrations, which the other two do not touch: there on the ground motions, median over the records)."""
    case, n_ground, key, truth, rel = FITS[example]
    camp = load_campaign(ic.cached_campaign(base, case, n_ground=n_ground, seed=0)["root"])
    errors, noise = _objective(camp, [r.id for r in camp.records])
    params, _err, _n = fit_effect(example, lambda e: float(errors(e).mean()), camp.specimen)
    assert params[key] == pytest.approx(truth, rel=rel)
    fitted = errors(make_effect(example, **params)) / noise
    neutral = errors(make_effect(example, **{key: EFFECTS[example].param_specs[key].neutral})) / noise
    fv = np.array([r.kind == "free_vibration" for r in camp.records])
    judged = fv if example == "pivot_friction" else ~fv
    assert np.all(fitted[fv] < 1.4)  # the free vibrations at their noise (the plain model's own: 1.0-1.34)
    assert np.median(fitted[judged]) < 1.1
    assert np.median(neutral[judged]) > 3.0  # the effect matters on these records


def test_a_term_module_without_a_source_file_is_keyed_by_its_functions_code():
    """A term typed into an interactive session has no source file: its compiled code keys its kernel, so a function
    typed again with another body gets a new kernel instead of the machine code of the old one."""
    import sys
    import types

    from housner.effects.codegen import _source_bytes

    mod = types.ModuleType("housner_test_session_terms")
    sys.modules[mod.__name__] = mod
    try:
        exec("def drag(phi, w, t, a, v, s, alpha, p2, q):\n    return -q[0] * w\n", mod.__dict__)
        first = _source_bytes(mod.__name__, ("drag",))
        exec("def drag(phi, w, t, a, v, s, alpha, p2, q):\n    return -2.0 * q[0] * w\n", mod.__dict__)
        assert first and _source_bytes(mod.__name__, ("drag",)) != first
    finally:
        del sys.modules[mod.__name__]
