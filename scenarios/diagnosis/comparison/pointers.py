"""Where to look next: the physical classes that the localisation and the recording order point to.

:func:`physical_classes` maps the localisation quantities in which a model
differs from the measurement (:meth:`housner.scenarios.diagnosis.comparison.record_comparison.Comparison.discrepancies`)
to the physical classes of :data:`CLASSES`, strongest first, each with its
supporting figures; :func:`order_drift` adds the ``drift`` class when the
records' excess errors, or the free vibrations' energy ratios, change along
the recording order. The verdict (:mod:`housner.scenarios.diagnosis.verdict.decision`)
names them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace

import numpy as np
from scipy.stats import kendalltau, norm

from housner._values import read_as
from housner.scenarios.diagnosis.comparison.localise import METRICS
from housner.scenarios.diagnosis.comparison.record_comparison import Comparison

__all__ = [
    "CLASSES",
    "MIN_RECORDS",
    "Z_DRIFT",
    "Evidence",
    "PointerClass",
    "evidence_beyond",
    "order_drift",
    "physical_classes",
]

#: |z| of the rank correlation between the records' excess errors and their recording order beyond
#: which the campaign is said to drift (two models tested, two-sided: 2 x 4.7e-4) [-].
Z_DRIFT = 3.5
#: Fewest records of a campaign (free vibration and ground motion) the verdict speaks on, and the drift test
#: needs [-].
MIN_RECORDS = 8

#: Localisation metric -> physical class it points to.
_CLASS_OF: dict[str, str] = {
    "energy_ratio": "impact",
    "energy_ratio_trend": "impact",
    "energy_ratio_scatter": "impact",
    "flight_ratio": "dissipation",
    "flight_ratio_trend": "dissipation",
    "p": "inertia",
    "alternation": "asymmetry",
    "onset_pos": "asymmetry",
    "onset_neg": "asymmetry",
    "withstood_pos": "asymmetry",
    "withstood_neg": "asymmetry",
    "first_uplift_pos": "asymmetry",
    "share_pos": "asymmetry",
    "tilt_offset": "setup",
    "tilt_slope": "compliance",
    "overturn_fraction": "response",
    "theta_max_median": "response",
    "onset_scatter": "vertical_input",
}
#: Physical class -> what it means, in words.
CLASSES: dict[str, str] = {
    "impact": "impact or contact physics: the energy lost per impact differs from the model's, changes with "
    "amplitude or varies from impact to impact (restitution law, where on the contact strip the impact acts)",
    "dissipation": "dissipation between impacts: energy is lost while the block rocks (air drag, friction or "
    "micro-slip at the pivot, a lossy interface)",
    "inertia": "inertia or foundation: the half-cycle durations depart from Housner's law (p, a compliant base, "
    "a flexible body)",
    "asymmetry": "asymmetry: the two directions differ (mass distribution, pivot geometry, a tilted table)",
    "setup": "set-up or sensor: the block reads a rotation while at rest (sensor offset, a tilted table)",
    "compliance": "base or body compliance: the block rotates before it lifts off (flexible foundation or body)",
    "vertical_input": "the ground input or the effective gravity: the uplift thresholds depart from g tan alpha in "
    "both directions alike, or vary from record to record with the table motion (a vertical table acceleration, "
    "an accelerometer gain, a table that rocks)",
    "drift": "a drift along the recording order: the block or the set-up changed during the campaign (wear of the "
    "contact, a fixture loosening, the temperature); the order of the [[record]] tables is the recording order",
    "response": "response amplitude: the peaks or the overturn fraction differ although the records' details "
    "do not say why (an intensity-dependent effect)",
}


@dataclass(frozen=True)
class Evidence:
    """One figure behind a physical class: a quantity of the measurement against the model's.

    Attributes
    ----------
    metric : str
        The quantity's key (a localisation metric, ``error_order``, ``energy_ratio_order``, ``flight_share``,
        or ``probe:NAME`` for a probe of physics outside the library).
    label : str
        What it is, in words ("" for a probe: :func:`housner.reports.diagnosis.words.evidence_text` says it from
        ``params`` and the errors).
    measured, measured_se : float
        The measurement's value and its standard error (a probe: the error with it [alpha]).
    model, model_se : float
        The model's (a probe: the error without it [alpha]).
    z : float
        Their difference over its standard error [-].
    params : dict
        A probe's fitted parameters (empty for every other figure).
    """

    metric: str
    label: str
    measured: float
    measured_se: float
    model: float
    model_se: float
    z: float
    params: dict = field(default_factory=dict)

    @property
    def is_probe(self) -> bool:
        return self.metric.startswith("probe:")

    def to_dict(self) -> dict:
        """The fields as plain data; ``params`` only for a probe (the other figures have none)."""
        data = asdict(self)
        if not self.params:
            del data["params"]
        return data


@dataclass(frozen=True)
class PointerClass:
    """A physical class to look at (:data:`CLASSES`), with the figures that point to it.

    Attributes
    ----------
    name : str
        The class (a key of :data:`CLASSES`); ``"class"`` in the JSON.
    meaning : str
    z : float
        The largest |z| of its evidence [-].
    evidence : tuple of Evidence
    source : str or None
        Whose localisation gave its figures: ``"final"`` (the model with the added effects), ``"plain"``, or None
        (not yet said); ``"from"`` in the JSON.
    """

    name: str
    meaning: str
    z: float
    evidence: tuple[Evidence, ...] = field(default_factory=tuple)
    source: str | None = None

    def to_dict(self) -> dict:
        out = {
            "class": self.name,
            "meaning": self.meaning,
            "z": self.z,
            "evidence": [e.to_dict() for e in self.evidence],
        }
        if self.source is not None:
            out["from"] = self.source
        return out

    @classmethod
    def from_dict(cls, data: dict) -> PointerClass:
        return cls(
            name=data["class"],
            meaning=data["meaning"],
            z=read_as(float, data["z"]),
            evidence=read_as(tuple[Evidence, ...], data["evidence"]),
            source=data.get("from"),
        )


def physical_classes(cmp: Comparison | None, z: float = 3.0) -> list[PointerClass]:
    """Physical classes the localisation points to, strongest first, each with its supporting figures (its ``z``:
    the largest |z| of its metrics)."""
    if cmp is None:
        return []
    strongest: dict[str, float] = {}  # class -> the largest |z| of its evidence
    evidence: dict[str, list[Evidence]] = {}
    found = cmp.discrepancies(z)
    zs = {k: zz for k, zz, *_ in found}
    # The energy ratio of seed eq. 8 is taken peak to peak: it holds the loss at the impact AND the loss
    # while the block rocks. When the loss between impacts (flight ratio) also differs, that is where
    # the energy goes. When it is not resolved, the share of the extra loss that the flight ratio puts
    # between the impacts decides (the likelier of the two): a friction moment at the pivot loses
    # (almost) all of it there, an impact law none.
    share = _flight_share(cmp.localisation()) if "energy_ratio" in zs else None
    flight = any(k.startswith("flight_ratio") for k in zs) or (share is not None and share[0] > 0.5)
    # Uplift thresholds that differ alike in both directions are the input's or gravity's (a gain on
    # the recorded acceleration, a vertical acceleration); differing one way only, or in opposite ways,
    # an asymmetry.
    sides = [(zs.get(f"onset_{d}"), zs.get(f"withstood_{d}")) for d in ("pos", "neg")]
    sign = [next((math.copysign(1.0, v) for v in side if v is not None), 0.0) for side in sides]
    symmetric = sign[0] != 0.0 and sign[0] == sign[1]
    for key, zz, m, x in found:
        c = _CLASS_OF.get(key, "response")
        if flight and key.startswith("energy_ratio") and key != "energy_ratio_scatter":
            c = "dissipation"
        if symmetric and key.startswith(("onset_", "withstood_")):
            c = "vertical_input"
        strongest[c] = max(strongest.get(c, 0.0), abs(zz))
        found_c = evidence.setdefault(c, [])
        if key == "energy_ratio" and share is not None:
            found_c.append(
                Evidence(
                    metric="flight_share",
                    label="share of the extra loss per half-cycle that the energy kept "
                    "between impacts puts between them (1: all of it, 0: none, at the impact)",
                    measured=share[0],
                    measured_se=share[1],
                    model=0.0,
                    model_se=0.0,
                    z=share[0] / share[1] if share[1] > 0 else math.inf,
                )
            )
        found_c.append(
            Evidence(
                metric=key,
                label=METRICS[key][0],
                measured=m.value,
                measured_se=m.se,
                model=x.value,
                model_se=x.se,
                z=zz,
            )
        )
    classes = [PointerClass(c, CLASSES[c], strongest[c], tuple(ev)) for c, ev in evidence.items()]
    return sorted(classes, key=lambda c: -c.z)


def _flight_share(loc: dict) -> tuple[float, float] | None:
    """Share of the extra energy loss per half-cycle that happens between impacts, and its standard error.

    The measured energy ratio c_m falls short of the model's c_x by a factor c_m / c_x; the energy kept
    between impacts f (flight ratio) says how much of that shortfall is lost while the block rocks:
    (1 - f_m / f_x) / (1 - c_m / c_x). None when either is not measured or the ratios agree.
    """
    try:
        (cm, cx), (fm, fx) = loc["energy_ratio"], loc["flight_ratio"]
    except KeyError:
        return None
    vals = (cm.value, cx.value, fm.value, fx.value, fm.se, fx.se)
    if not all(math.isfinite(v) for v in vals) or cx.value <= 0 or fx.value <= 0 or fm.value <= 0:
        return None
    deficit = 1.0 - cm.value / cx.value
    if abs(deficit) < 1e-9:
        return None
    q = fm.value / fx.value
    se = q * math.hypot(fm.se / fm.value, fx.se / fx.value) / abs(deficit)
    return (1.0 - q) / deficit, se


def _energy_drift(energy) -> tuple[float, float, float] | None:
    """Slope of the free vibrations' energy ratio per impact against the recording position [1/record],
    its standard error and z, with the amplitude dependence (a quadratic in the amplitude) held out.

    ``energy`` is (record position, amplitude [alpha], energy ratio [-]) per impact. None when fewer
    than two records or too few impacts carry it.
    """
    if energy is None:
        return None
    pos, amp, c = (np.asarray(v, dtype=float) for v in energy)
    ok = np.isfinite(pos) & np.isfinite(amp) & np.isfinite(c)
    pos, amp, c = pos[ok], amp[ok], c[ok]
    if np.unique(pos).size < 2 or c.size < 8:
        return None
    A = np.column_stack((np.ones_like(amp), amp, amp**2, pos))
    coef, *_ = np.linalg.lstsq(A, c, rcond=None)
    res = c - A @ coef
    s2 = float(res @ res) / (c.size - A.shape[1])
    try:
        se = math.sqrt(max(float(s2 * np.linalg.inv(A.T @ A)[3, 3]), 0.0))
    except np.linalg.LinAlgError:
        return None
    if not se > 0:
        return None
    return float(coef[3]), se, float(coef[3]) / se


def order_drift(excess: Sequence[np.ndarray], energy=None) -> PointerClass | None:
    """A drift along the recording order, as a physical class of :func:`physical_classes`, or None.

    Parameters
    ----------
    excess : sequence of ndarray
        Per record, in campaign (recording) order: a model's held-out error less its floor [alpha],
        for each model judged (the plain model, the final one).
    energy : tuple of ndarray, optional
        The measured free vibrations' (record position, amplitude [alpha], energy ratio [-]) per
        impact (:class:`housner.scenarios.diagnosis.comparison.localise.Features`).

    Returns
    -------
    PointerClass or None
        The ``drift`` class, when either test's two-sided |z| exceeds :data:`Z_DRIFT`:

        * Kendall's tau of the excess error against the record's position, for the model where it
          is strongest. Under a physics that does not change during the campaign the records' excess
          errors are exchangeable, so the rank test holds its level whatever their (heavy-tailed,
          chaotic) distribution;
        * the slope of the free vibrations' energy ratio per impact against the position of their
          record, the amplitude dependence held out (a restitution that wears shows here first: the
          free vibrations are not chaotic).
    """
    evidence = []
    best = None
    for e in excess:
        e = np.asarray(e, dtype=float)
        ok = np.flatnonzero(np.isfinite(e))
        if ok.size < MIN_RECORDS:
            continue
        res = kendalltau(ok, e[ok])
        if not math.isfinite(res.statistic):
            continue
        z = math.copysign(float(norm.isf(max(res.pvalue, 1e-300) / 2)), res.statistic)
        n = ok.size
        if best is None or abs(z) > abs(best[1]):
            best = (float(res.statistic), z, math.sqrt(2 * (2 * n + 5) / (9 * n * (n - 1))))
    if best is not None:
        tau, z, se = best
        trend = "grows" if tau > 0 else "falls"
        evidence.append(
            Evidence(
                metric="error_order",
                label=f"the model's excess error {trend} along the recording order (Kendall's tau)",
                measured=tau,
                measured_se=se,
                model=0.0,
                model_se=0.0,
                z=z,
            )
        )
    ed = _energy_drift(energy)
    if ed is not None:
        slope, se, z = ed
        evidence.append(
            Evidence(
                metric="energy_ratio_order",
                label="energy ratio per impact of the free vibrations against their record's position in the "
                "recording order, amplitude held out (slope per record)",
                measured=slope,
                measured_se=se,
                model=0.0,
                model_se=0.0,
                z=z,
            )
        )
    evidence = sorted((ev for ev in evidence if abs(ev.z) > Z_DRIFT), key=lambda ev: -abs(ev.z))
    if not evidence:
        return None
    return PointerClass("drift", CLASSES["drift"], abs(evidence[0].z), tuple(evidence))


def evidence_beyond(classes: list[PointerClass], z: float) -> list[PointerClass]:
    """The classes of :func:`physical_classes` with only their evidence beyond ``z`` standard errors."""
    out = []
    for c in classes:
        ev = tuple(e for e in c.evidence if abs(e.z) > z)
        if ev:
            out.append(replace(c, z=max(abs(e.z) for e in ev), evidence=ev))
    return out
