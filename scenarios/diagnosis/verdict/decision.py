"""The diagnosis' verdict: is the remaining misfit physics, or what a correct model shows anyway?

A held-out time-history error is only meaningful against the error that a
*correct* model would show on the same records. That floor is measured from
the campaign itself by a parametric bootstrap
(:func:`housner.scenarios.diagnosis.verdict.correct_model_floor.measure_floor`), and the real
held-out errors are tested against it record by record
(:func:`housner.scenarios.diagnosis.verdict.residual_test.residual_test`): a misfit is
*significant* when z > :data:`Z_MISFIT` and its size *matters* when the
error is more than :data:`RATIO_MISFIT` times the floor. The localisation
says where to look (:func:`housner.scenarios.diagnosis.comparison.pointers.physical_classes`,
:func:`housner.scenarios.diagnosis.comparison.pointers.order_drift`).

:func:`decide` turns the residual of the plain model and of the final model,
the effects selected and the distributions into one of five statuses:
``no_misfit``, ``explained``, ``partly_explained``, ``unexplained``,
``inconclusive``, with a paragraph that says it in words, where the misfit
shows (localisation items), and which physical classes to look at next
(:func:`physical_classes`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace

import numpy as np
from scipy.stats import norm

from housner._values import read_as, to_data
from housner.scenarios.diagnosis.comparison.pointers import (
    CLASSES,
    MIN_RECORDS,
    Evidence,
    PointerClass,
    evidence_beyond,
    physical_classes,
)
from housner.scenarios.diagnosis.comparison.record_comparison import Comparison
from housner.scenarios.diagnosis.selection.probes import ProbeFinding
from housner.scenarios.diagnosis.verdict.residual_test import (
    DETECTABLE_RATIO,
    RATIO_MISFIT,
    Residual,
)
from housner.scenarios.diagnosis.verdict.status import status_rule

__all__ = [
    "DIST_LEVEL",
    "DistributionMisfit",
    "Z_LOCAL",
    "Verdict",
    "VerdictFacts",
    "decide",
    "distribution_checks",
    "pointer_classes",
]

#: |z| beyond which a localisation quantity of a model says it misses something even when its errors
#: are at the floor [-]: with the 17 quantities of housner.scenarios.diagnosis.comparison.localise.METRICS tested at
# once, a
#: two-sided 6e-5 each keeps the chance of a false alarm per model near 0.1 % (Bonferroni).
Z_LOCAL = 4.0
#: Significance level of each distribution check (KS of theta_max/alpha, overturn fraction) [-].
DIST_LEVEL = 0.01


@dataclass(frozen=True)
class DistributionMisfit:
    """A significant difference between the measured and the model's ground-motion outcomes
    (:func:`distribution_checks`).

    Attributes
    ----------
    kind : str
        ``"ks"``: the theta_max/alpha distributions differ (Kolmogorov-Smirnov); ``"overturns"``: the overturn
        fractions differ (a two-proportion z-test).
    distance, pvalue : float
        For ``"ks"``: the largest gap between the two cumulative distributions [-] and its p-value [-].
    measured, model, n : int
        For ``"overturns"``: the records that overturned, measured and in the model, out of ``n``.
    z : float
        For ``"overturns"``: the difference of the fractions in standard errors [-].
    """

    kind: str
    distance: float = math.nan
    pvalue: float = math.nan
    measured: int = 0
    model: int = 0
    n: int = 0
    z: float = math.nan


def distribution_checks(cmp: Comparison | None) -> list[DistributionMisfit]:
    """Distribution misfits of the ground-motion records, each significant at :data:`DIST_LEVEL` (empty when none
    is)."""
    out: list[DistributionMisfit] = []
    if cmp is None or cmp.distribution is None or cmp.distribution.measured.size < 5:
        return out
    d = cmp.distribution
    if d.ks.pvalue < DIST_LEVEL:
        out.append(DistributionMisfit("ks", distance=float(d.ks.distance), pvalue=float(d.ks.pvalue)))
    n = d.measured.size
    k1, k2 = int(np.isinf(d.measured).sum()), int(np.isinf(d.model).sum())
    pool = (k1 + k2) / (2 * n)
    if 0 < pool < 1:
        zz = (k2 - k1) / n / math.sqrt(2 * pool * (1 - pool) / n)
        if 2 * norm.sf(abs(zz)) < DIST_LEVEL:
            out.append(DistributionMisfit("overturns", measured=k1, model=k2, n=int(n), z=float(zz)))
    return out


# ----------------------------------------------------------------------------
# the verdict
@dataclass(frozen=True)
class VerdictFacts:
    """What the verdict is drawn from (:func:`decide`): the residuals, the model judged, the pointers.

    Attributes
    ----------
    n_records : int
    baseline, final : Residual
        The plain and the final model's held-out errors against their floors.
    selected, added : sequence of str
        The effects the search added and those added by hand.
    model : list of str
        The effects of the final model (by hand first).
    params : dict
        Effect -> its fitted parameters in the final model.
    library : sequence of str
        The effects the search tried.
    drift : PointerClass or None
        :func:`order_drift`'s class, if any.
    family : str
        The correct integrators the final model's floor was measured over.
    classes : list of PointerClass
        The physical classes to look at, strongest first (drift and probes first).
    final_classes : list of PointerClass
        Those the final model's localisation points to.
    local_plain, local_final : list of PointerClass
        The plain and final model's classes with only their evidence beyond :data:`Z_LOCAL`.
    dist_plain, dist_final : list of DistributionMisfit
        Their distribution misfits (:func:`distribution_checks`).
    plain_misfit, final_misfit : bool
        Whether each residual is a misfit (:func:`status_rule`).
    powered : bool
        Whether the records would show a misfit of :data:`DETECTABLE_RATIO` x the floor.
    probed : bool
        Whether a probe of physics outside the library lowered the error significantly.
    family_plain : str
        The plain model's (its own family loop; ``""``: ``family``).
    search : str
        What the search did: ``"ran"`` (it tried ``library``), ``"off"`` (no candidate effect was given),
        ``"none_left"`` (no candidate could be tried: max_effects 0, or each already in the model or
        incompatible with it), ``"skipped"`` (the training error was already at the sensor noise).
    """

    n_records: int
    baseline: Residual
    final: Residual
    selected: Sequence[str]
    added: Sequence[str]
    model: list[str]
    params: dict
    library: Sequence[str]
    drift: PointerClass | None
    family: str
    classes: list[PointerClass]
    final_classes: list[PointerClass]
    local_plain: list[PointerClass]
    local_final: list[PointerClass]
    dist_plain: list[DistributionMisfit]
    dist_final: list[DistributionMisfit]
    plain_misfit: bool
    final_misfit: bool
    powered: bool
    probed: bool
    family_plain: str = ""
    search: str = "ran"

    def to_dict(self) -> dict:
        """The facts as plain data, less what the verdict's JSON holds already (the two residuals, and the classes:
        its ``next``)."""
        out = {}
        for f in fields(self):
            if f.name in ("baseline", "final", "classes"):
                continue
            v = getattr(self, f.name)
            if f.name in ("drift",):
                v = None if v is None else v.to_dict()
            elif f.name in ("final_classes", "local_plain", "local_final"):
                v = [c.to_dict() for c in v]
            out[f.name] = to_data(v)
        return out

    @classmethod
    def from_dict(cls, data: dict, *, baseline: Residual, final: Residual, classes: list[PointerClass]) -> VerdictFacts:
        """The facts :meth:`to_dict` wrote, with what the verdict's JSON holds besides."""

        def pointers(key: str) -> list[PointerClass]:
            return [PointerClass.from_dict(c) for c in data[key]]

        return cls(
            n_records=int(data["n_records"]),
            baseline=baseline,
            final=final,
            selected=tuple(data["selected"]),
            added=tuple(data["added"]),
            model=list(data["model"]),
            params={n: {k: read_as(float, v) for k, v in p.items()} for n, p in data["params"].items()},
            library=tuple(data["library"]),
            drift=None if data["drift"] is None else PointerClass.from_dict(data["drift"]),
            family=data["family"],
            classes=list(classes),
            final_classes=pointers("final_classes"),
            local_plain=pointers("local_plain"),
            local_final=pointers("local_final"),
            dist_plain=read_as(list[DistributionMisfit], data["dist_plain"]),
            dist_final=read_as(list[DistributionMisfit], data["dist_final"]),
            plain_misfit=bool(data["plain_misfit"]),
            final_misfit=bool(data["final_misfit"]),
            powered=bool(data["powered"]),
            probed=bool(data["probed"]),
            family_plain=data["family_plain"],
            search=data["search"],
        )

    @property
    def records_needed(self) -> int:
        """Ground-motion records to add for the power the verdict promises."""
        return self.final.records_needed if self.model else self.baseline.records_needed


@dataclass(frozen=True)
class Verdict:
    """What the diagnosis can claim: the status and the facts it rests on
    (:mod:`housner.reports.diagnosis.verdict_text` says it in words).

    Attributes
    ----------
    status : str
        One of :data:`housner.scenarios.diagnosis.verdict.status.STATUSES`.
    residual : Residual
        The final model's held-out error against its floor.
    baseline : Residual
        The plain model's.
    facts : VerdictFacts
        What the status was drawn from.
    next : list of PointerClass
        Physical classes to look at, strongest first (:func:`physical_classes`).
    records_needed : int
        For ``inconclusive``: ground-motion records to add.
    """

    status: str
    residual: Residual
    baseline: Residual
    facts: VerdictFacts
    next: list[PointerClass] = field(default_factory=list)
    records_needed: int = 0

    @property
    def where(self) -> list[Evidence]:
        """The localisation quantities where the final model still differs from the measurement (a drift along
        the recording order first)."""
        drift = list(self.facts.drift.evidence) if self.facts.drift is not None else []
        return drift + [ev for c in self.facts.final_classes for ev in c.evidence]

    @property
    def distribution(self) -> list[DistributionMisfit]:
        """The final model's distribution misfits."""
        return list(self.facts.dist_final)

    def to_dict(self) -> dict:
        """The verdict as its JSON holds it, less its words (``text``, ``where``, ``distribution``), which
        :func:`housner.reports.diagnosis.document.diagnosis_document` adds."""
        r = self.residual
        return {
            "status": self.status,
            "residual": {"error": r.error, "floor": r.floor, "ratio": r.ratio, "z": r.z},
            "residual_detail": r.to_dict(),
            "baseline_residual": self.baseline.to_dict(),
            "next": [c.to_dict() for c in self.next],
            "records_needed": self.records_needed,
            "facts": self.facts.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: dict) -> Verdict:
        """The verdict a diagnosis JSON holds (its ``residual`` is the head of ``residual_detail``; its words are
        not read: they follow from the facts)."""
        residual = Residual.from_dict(data["residual_detail"])
        baseline = Residual.from_dict(data["baseline_residual"])
        nxt = [PointerClass.from_dict(c) for c in data["next"]]
        return cls(
            status=data["status"],
            residual=residual,
            baseline=baseline,
            facts=VerdictFacts.from_dict(data["facts"], baseline=baseline, final=residual, classes=nxt),
            next=nxt,
            records_needed=int(data["records_needed"]),
        )


def decide(
    *,
    n_records: int,
    baseline: Residual,
    final: Residual,
    selected: Sequence[str],
    params: dict[str, dict],
    baseline_cmp: Comparison | None,
    final_cmp: Comparison | None,
    library: Sequence[str],
    added: Sequence[str] = (),
    drift: PointerClass | None = None,
    family: str = "",
    probes: Sequence[ProbeFinding] = (),
    family_plain: str = "",
    search: str | None = None,
) -> Verdict:
    """The status (:func:`status_rule`) and its paragraph (:func:`verdict_text`) from the residuals, the effects
    in the final model and the localisation.

    ``selected`` are the effects the search added, ``added`` those added by hand (both in the final
    model, which is the one judged); ``drift`` is :func:`order_drift`'s class, if any; ``family`` the
    correct integrators the final model's floor was measured over
    (:data:`housner.scenarios.diagnosis.verdict.integrator_families.FAMILIES`), ``family_plain`` the plain model's;
    ``search``
    what the search did (:class:`VerdictFacts`; default ``"ran"`` when ``library`` is given, else ``"off"``).
    """
    model = [*added, *[n for n in selected if n not in added]]
    base_classes = physical_classes(baseline_cmp)
    final_classes = physical_classes(final_cmp)
    classes = pointer_classes(base_classes, final_classes, probes, drift, has_effects=bool(model))
    # a localisation quantity beyond Z_LOCAL standard errors points to where to look; it is no misfit by
    # itself (the status follows from the residual's tests alone: status_rule)
    local_plain = evidence_beyond(base_classes, Z_LOCAL)
    local_final = evidence_beyond(final_classes, Z_LOCAL)
    # the residual's tests: against the floor, along the recording order, and against a probe of physics
    # outside the library (held-out errors, each at the verdict's level); a localisation quantity beyond Z_LOCAL
    # counts only for a residual above the floor's band (ratio > RATIO_MISFIT) that its own test cannot call
    # significant: it never turns a residual at the floor into a misfit
    residual_tests = drift is not None or bool(probes)
    facts = VerdictFacts(
        n_records=n_records,
        baseline=baseline,
        final=final,
        selected=selected,
        added=added,
        model=model,
        params=params,
        library=library,
        drift=drift,
        family=family,
        classes=classes,
        final_classes=final_classes,
        local_plain=local_plain,
        local_final=local_final,
        dist_plain=distribution_checks(baseline_cmp),
        dist_final=distribution_checks(final_cmp),
        plain_misfit=baseline.misfit or residual_tests or (bool(local_plain) and baseline.ratio > RATIO_MISFIT),
        final_misfit=final.misfit or residual_tests or (bool(local_final) and final.ratio > RATIO_MISFIT),
        powered=final.detectable_ratio <= DETECTABLE_RATIO,
        probed=bool(probes),
        family_plain=family_plain or family,
        search=search or ("ran" if library else "off"),
    )
    status = status_rule(
        n_records >= MIN_RECORDS, bool(facts.model), facts.plain_misfit, facts.final_misfit, facts.powered
    )
    return Verdict(
        status,
        final,
        baseline,
        facts,
        classes,
        facts.records_needed if status == "inconclusive" else 0,
    )


def pointer_classes(
    base_classes: list[PointerClass],
    final_classes: list[PointerClass],
    probes: Sequence[ProbeFinding],
    drift: PointerClass | None,
    has_effects: bool = False,
) -> list[PointerClass]:
    """The physical classes to look at, strongest first: a drift along the recording order, then the probes'
    classes, then what the localisation points to: the plain model's classes in their order (what differs from
    Housner's physics names the family: on the independent generator's pivot-friction campaign the plain model
    points to dissipation, the model with the restitution the search adds to impact), then those only the final
    model shows.

    Each class carries whose figures it gives (``source``): where the model with effects (``has_effects``) still
    shows a class, its own evidence (``"final"``); otherwise the plain model's (``"plain"``), which
    :func:`pointer_text` says.
    """
    final = {c.name: c for c in final_classes} if has_effects else {}
    classes = [
        replace(final[c.name], source="final") if c.name in final else replace(c, source="plain") for c in base_classes
    ]
    have = {c.name for c in classes}
    classes += [replace(c, source="final") for c in final_classes if has_effects and c.name not in have]
    # a probe of physics outside the library that lowers the error significantly is the most direct
    # pointer there is: its class first (housner.scenarios.diagnosis.selection.probes)
    for found in sorted(probes, key=lambda p: p.z):
        evidence = Evidence(
            metric=f"probe:{found.probe}",
            label="",
            measured=found.error_with,
            measured_se=found.se,
            model=found.error,
            model_se=0.0,
            z=found.z,
            params=dict(found.params),
        )
        old = [c for c in classes if c.name == found.class_name]
        entry = PointerClass(
            name=found.class_name,
            meaning=CLASSES[found.class_name],
            z=abs(found.z),
            evidence=(evidence, *(old[0].evidence if old else ())),
            source="final" if has_effects else "plain",
        )
        classes = [entry, *[c for c in classes if c.name != found.class_name]]
    if drift is not None:
        # a physics that changes along the recording order is what no constant effect explains: named first
        classes = [drift, *[c for c in classes if c.name != "drift"]]
    return classes
