"""The motion factory: a scenario's ground motions at model scale, and the facts the report shows.

The catalogue describes motions (:mod:`housner.scenarios.catalogue`: it runs nothing); this module
makes them: records scaled by ``amplitude`` and compressed in time by sqrt(S), RDK ensembles
(plain or spectrum-matched) fitted once per record content (a small fit cache), pulses on a grid,
free-vibration releases.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from housner._values import JsonValue
from housner.errors import one_line, unknown_choice
from housner.motion import GroundMotion
from housner.pulse_response import pulses
from housner.scenarios.motions import bands, rdk, rdk_match
from housner.scenarios.motions.records import load_record

__all__ = [
    "DEFAULT_RDK_MODEL",
    "RDK_MODELS",
    "BandCheck",
    "BandRow",
    "BandTable",
    "MatchedGain",
    "MotionFacts",
    "RdkParameter",
    "RecordFacts",
    "build_motions",
]

#: Ground-motion models of source "rdk": the published RDK model, and the spectrally
#: matched ensemble of :mod:`housner.scenarios.motions.rdk_match`.
RDK_MODELS = ("rdk2010", "matched")
DEFAULT_RDK_MODEL = "rdk2010"


@dataclass(frozen=True, eq=False)
class RecordFacts(JsonValue):
    """A record's facts: ``name``, ``provenance``, step ``dt`` [s], samples ``n``; for a file also ``file`` (as
    written), ``path`` (resolved), ``sha256`` and its measured ``channels``. A fact not stated is None."""

    name: str | None = None
    provenance: str | None = None
    dt: float | None = None
    n: int | None = None
    file: str | None = None
    path: str | None = None
    sha256: str | None = None
    channels: tuple[str, ...] | None = None
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class RdkParameter(JsonValue):
    """A fitted parameter stated with its unit and meaning (``{"value", "unit", "description"}``), where a model's
    table gives one so rather than as a plain number."""

    value: float | str | None = None
    unit: str | None = None
    description: str | None = None


@dataclass(frozen=True, eq=False)
class MatchedGain(JsonValue):
    """The spectral gain of the matched RDK model (:class:`housner.scenarios.motions.rdk_match.MatchedRDK`).

    ``gain`` [-] at ``gain_centres_s`` [s] (band centres, prototype scale), the FIR's length [s], the motions
    (``n_fit``) and ``iterations`` of the fit with the worst band ratio of each, and the fit's seed.
    """

    model: str | None = None
    gain_centres_s: tuple[float, ...] = ()
    gain: tuple[float, ...] = ()
    fir_length_s: float | None = None
    n_fit: int | None = None
    iterations: int | None = None
    worst_band_ratio_per_iteration: tuple[float, ...] = ()
    fit_seed: str | None = None
    extra: dict = field(default_factory=dict)

    _ALWAYS = ("fit_seed",)


@dataclass(frozen=True, eq=False)
class BandRow(JsonValue):
    """One third-octave band of a band check: its centre and edges [s], the ensemble-mean / record ratio, its
    95 % interval and ``verdict`` (PASS or FAIL)."""

    centre_s: float | None = None
    lo_s: float | None = None
    hi_s: float | None = None
    ratio: float | None = None
    ci95_lo: float | None = None
    ci95_hi: float | None = None
    verdict: str | None = None


@dataclass(frozen=True, eq=False)
class BandTable(JsonValue):
    """One quantity's bands (PSa or Sd): the period range checked [s], whether every band passed, the bands."""

    range_s: tuple[float, ...] = ()
    passed: bool | None = None
    bands: tuple[BandRow, ...] = ()


@dataclass(frozen=True, eq=False)
class BandCheck(JsonValue):
    """The band check of an ensemble against its record (:func:`housner.scenarios.motions.bands.band_check`).

    Attributes
    ----------
    what : str
        What was compared, in words.
    record : str
        The record's name.
    damping : float
        Damping ratio of the spectra [-].
    bounds : tuple of float
        The accepted range of a band's ratio [-].
    passed : bool
        Whether every band of both quantities passed.
    psa, sd : BandTable
    """

    what: str | None = None
    record: str | None = None
    damping: float | None = None
    bounds: tuple[float, ...] = ()
    passed: bool | None = None
    psa: BandTable | None = None
    sd: BandTable | None = None


@dataclass(frozen=True, eq=False)
class MotionFacts(JsonValue):
    """The facts of a run's ground motions (:func:`build_motions`'s, or a campaign's), as run.json keeps them.

    A fact that does not apply to the motions' source is None (and not written).

    Attributes
    ----------
    source : str or None
        ``rdk``, ``record``, ``records``, ``pulses``, ``free_vibration`` or ``campaign``.
    S : float or None
        Size ratio prototype / model [-].
    records : tuple of RecordFacts or None
        A suite's records, one per motion.
    record : RecordFacts or None
        The record (of source ``record`` or ``rdk``).
    model, seed, rdk_params, matched_gain, band_check
        An RDK ensemble's model, seed, fitted parameters (the model's table: name, units in it, -> value, or an
        :class:`RdkParameter`), the matched model's gain and the band check against the record.
    theta0_over_alpha : tuple of float or None
        Free vibration: the release amplitudes [-].
    pulse, omega_ratio, accel_ratio
        Pulses: the shape and the grid of omega_p/p and a_p/(g tan alpha) [-], one point per motion.
    campaign, n_ground_motion, n_free_vibration
        A measured campaign's name and its records of each kind.
    """

    source: str | None = None
    S: float | None = None
    records: tuple[RecordFacts, ...] | None = None
    record: RecordFacts | None = None
    model: str | None = None
    seed: int | None = None
    rdk_params: dict[str, float | str | RdkParameter] | None = None
    matched_gain: MatchedGain | None = None
    band_check: BandCheck | None = None
    theta0_over_alpha: tuple[float, ...] | None = None
    pulse: str | None = None
    omega_ratio: tuple[float, ...] | None = None
    accel_ratio: tuple[float, ...] | None = None
    campaign: str | None = None
    n_ground_motion: int | None = None
    n_free_vibration: int | None = None
    extra: dict = field(default_factory=dict)


def build_motions(
    scenario, n: int | None = None, *, seed: int | None = None, band_check: bool = False
) -> tuple[list[GroundMotion], dict]:
    """Generate a scenario's motions at model scale, and metadata for the report.

    Parameters
    ----------
    scenario : housner.scenarios.catalogue.Scenario
    n : int, optional
        Number of motions (RDK ensembles only; motion i does not depend on n).
    seed : int, optional
        Override the scenario's seed (RDK only).
    band_check : bool
        RDK only: also compare the ensemble's mean 5 % spectra with the
        record's, per third-octave band (PSa 0.05-3 s, Sd 0.5-3 s, at
        prototype scale, before ``amplitude``; :func:`housner.scenarios.motions.bands.band_check`).
        About 2 s per 100 motions, so off unless asked (the runner asks).

    Returns
    -------
    motions : list of GroundMotion
    meta : dict
        Source-specific facts: ``S``; the ``record`` (name, provenance,
        dt [s], n; for a file also ``file``, ``path``, ``sha256``) or, for a
        suite, ``records`` (one such dict per motion); for RDK the ``model``,
        ``rdk_params``, ``seed``, for the matched model ``matched_gain``,
        and with ``band_check`` the ``band_check`` table.
    """
    src = scenario.source
    meta: dict[str, Any] = {"source": src, "S": scenario.S}
    amp = float(scenario.motions.get("amplitude", 1.0))
    if src == "records":
        suite = scenario.record_files()["records"]
        meta["records"] = [facts for _, facts in suite]
        return [_to_model(g, amp, scenario.S) for g, _ in suite], meta
    if src in ("rdk", "record"):
        record, meta["record"] = _record(scenario)
        if src == "record":
            return [_to_model(record, amp, scenario.S)], meta
        proto = _rdk_ensemble(scenario, record, n, seed, band_check, meta)
        return [_to_model(g, amp, scenario.S) for g in proto], meta
    if src == "free_vibration":
        return _free_vibration_motions(scenario, meta), meta
    return _pulse_motions(scenario, meta), meta


def _rdk_ensemble(scenario, record: GroundMotion, n, seed, band_check: bool, meta: dict) -> list[GroundMotion]:
    """The prototype-scale RDK ensemble of a scenario fitted to ``record``; its facts go into ``meta``
    (``model``, ``seed``, ``rdk_params``, for the matched model ``matched_gain``, and ``band_check``)."""
    m = scenario.motions
    if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1):
        raise ValueError(f"`n` (number of motions) must be a positive integer, got {n!r}")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ValueError(f"`seed` must be a non-negative integer, got {seed!r}")
    n = int(m.get("n", 100)) if n is None else int(n)
    seed = int(m.get("seed", 0)) if seed is None else int(seed)
    model = m.get("model", DEFAULT_RDK_MODEL)
    try:
        fit = _fit(model, record)
    except ValueError as e:  # a user's record the model cannot be fitted to
        raise scenario.error(
            "record", f"[motions] cannot fit model {model!r} to record {record.name!r}: {one_line(e)}"
        ) from None
    meta["model"] = model
    meta["seed"] = seed
    if model == "matched":
        meta["rdk_params"] = fit.params.describe()
        meta["matched_gain"] = _gain_facts(fit)
        proto = rdk_match.simulate_matched(fit, n, seed)
    else:
        meta["rdk_params"] = fit.describe()
        proto = rdk.simulate(fit, n, seed)
    if band_check:
        meta["band_check"] = _band_facts(proto, record, seed)
    return proto


def _free_vibration_motions(scenario, meta: dict) -> list[GroundMotion]:
    """Free-vibration releases from rest at theta0/alpha of the scenario (facts into ``meta``)."""
    m = scenario.motions
    alpha = scenario.specimen.alpha
    dur = float(m.get("duration", 10.0))
    dt = float(m.get("dt", 0.002))
    motions = [
        GroundMotion.free_vibration(a * alpha, dur, dt, name=f"release {a:.2f} alpha") for a in m["theta0_over_alpha"]
    ]
    meta["theta0_over_alpha"] = list(m["theta0_over_alpha"])
    return motions


def _pulse_motions(scenario, meta: dict) -> list[GroundMotion]:
    """One pulse per point of the scenario's grid of omega_p/p and a_p/(g tan alpha) (facts into ``meta``)."""
    m = scenario.motions
    W, A = scenario.pulse_grid()
    p = scenario.specimen.p
    a_up = scenario.specimen.uplift_acceleration
    dt = float(m.get("dt", 0.002))
    kind = m.get("pulse", "symmetric_ricker")
    motions = []
    for w, a in zip(W, A, strict=True):
        if kind == "one_sine":
            g = pulses.one_sine(a * a_up, w * p, dt=dt, p=p)
        elif kind == "mavroeidis_papageorgiou":
            shape = {k: float(m[k]) for k in ("gamma", "nu") if k in m}
            g = pulses.mavroeidis_papageorgiou(a * a_up, w * p, dt=dt, p=p, **shape)
        else:
            g = pulses.ricker(a * a_up, w * p, kind=kind.split("_")[0], dt=dt, p=p)
        motions.append(
            GroundMotion(g.acc, g.dt, f"{kind} w/p={w:.3g} a/gtan={a:.3g}", g.provenance, g.theta0, g.theta_dot0)
        )
    meta.update({"pulse": kind, "omega_ratio": W.tolist(), "accel_ratio": A.tolist()})
    if kind == "mavroeidis_papageorgiou":
        meta.update({k: float(m[k]) for k in ("gamma", "nu") if k in m})
    return motions


def _record(scenario) -> tuple[GroundMotion, dict]:
    """The record of an rdk or record source, and its facts (name, provenance, dt, n; file and sha256)."""
    files = scenario.record_files()
    if "record" in files:
        return files["record"][0]
    record = load_record(scenario.motions.get("record", "elcentro"))
    return record, {"name": record.name, "provenance": record.provenance, "dt": record.dt, "n": record.n}


def _to_model(g: GroundMotion, amplitude: float, S: float) -> GroundMotion:
    """A prototype-scale motion (record or simulated) times ``amplitude``, compressed in time by sqrt(S)."""
    return g.scaled(amplitude=amplitude).to_model_scale(S)


#: Fitted ground-motion models, oldest first: (model, record name, content hash of the record's
#: samples and step) -> RDKParams or MatchedRDK. A record file that changes has another hash, so
#: its fit is redone; the fits are deterministic (fixed fit seed).
_FITS: OrderedDict[tuple[str, str, str], Any] = OrderedDict()
_FITS_SIZE = 8


def _fit(model: str, record: GroundMotion):
    """The model of ``RDK_MODELS`` fitted to ``record`` (cached, see :data:`_FITS`)."""
    key = (model, record.name, record.content_hash())
    if key in _FITS:
        _FITS.move_to_end(key)
        return _FITS[key]
    if model == "matched":
        fit = rdk_match.fit_matched(record, params=_fit(DEFAULT_RDK_MODEL, record))
    elif model == DEFAULT_RDK_MODEL:
        fit = rdk.fit(record)
    else:
        raise unknown_choice("RDK model", model, RDK_MODELS)
    _FITS[key] = fit
    while len(_FITS) > _FITS_SIZE:
        _FITS.popitem(last=False)
    return fit


def _gain_facts(fit) -> dict:
    """The spectral gain of a MatchedRDK as plain data (units in the keys)."""
    d = fit.describe()
    keys = ("gain_centres_s", "gain", "fir_length_s", "n_fit", "iterations", "worst_band_ratio_per_iteration")
    return {"model": d["model"], **{k: d[k] for k in keys}, "fit_seed": d["fit_seed"]}


def _band_facts(proto: list[GroundMotion], record: GroundMotion, seed: int) -> dict:
    """The band check of a prototype-scale ensemble against its record, as plain data for run.json."""
    check = bands.band_check(proto, record)
    keep = ("centre_s", "lo_s", "hi_s", "ratio", "ci95_lo", "ci95_hi", "verdict")

    def table(t, t_range) -> dict:
        bands = [{k: row[k] for k in keep} for row in t.rows()]
        return {"range_s": list(t_range), "passed": t.passed, "bands": bands}

    return {
        "what": (
            f"5 % damped spectra, mean of {len(proto)} motions (seed {seed}) / record {record.name!r}, "
            "per third-octave band, at prototype scale, before 'amplitude'"
        ),
        "record": record.name,
        "damping": check.damping,
        "bounds": list(check.psa.bounds),
        "passed": check.passed,
        "psa": table(check.psa, bands.DEFAULT_PSA_RANGE),
        "sd": table(check.sd, bands.DEFAULT_SD_RANGE),
    }
