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
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.stats import norm

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
    Z_MISFIT,
    GroupResidual,
    Residual,
)
from housner.scenarios.diagnosis.verdict.status import status_rule
from housner.scenarios.diagnosis.verdict.verdict_words import (
    Z_LEGEND,
    Z_LOCAL_LEGEND,
    evidence_text,
    family_text,
    probe_words,
    z_text,
)

__all__ = [
    "DIST_LEVEL",
    "Z_LOCAL",
    "Verdict",
    "VerdictFacts",
    "decide",
    "distribution_checks",
    "pointer_classes",
    "pointer_text",
    "verdict_text",
]

#: |z| beyond which a localisation quantity of a model says it misses something even when its errors
#: are at the floor [-]: with the 17 quantities of housner.scenarios.diagnosis.comparison.localise.METRICS tested at
# once, a
#: two-sided 6e-5 each keeps the chance of a false alarm per model near 0.1 % (Bonferroni).
Z_LOCAL = 4.0
#: Significance level of each distribution check (KS of theta_max/alpha, overturn fraction) [-].
DIST_LEVEL = 0.01


def _groups_text(r: Residual, legend: bool = False) -> str:
    """Each group's error over its floor with its z; ``legend``: say once what z is (its first appearance)."""
    names = {"ground_motion": "ground motions", "free_vibration": "free vibrations"}

    def one(k: str, g: GroupResidual) -> str:
        if k != "ground_motion":
            return f"{names[k]} {g.ratio:.2f}x, {z_text(g.z)}"
        # the typical record first (10 %-trimmed); the mean, when the few records chaos carries off weigh on it
        out = f"{names[k]} {g.ratio_trimmed:.2f}x for the typical record (10 %-trimmed mean), {z_text(g.z_trimmed)}"
        if abs(g.ratio_trimmed - g.ratio) > 0.05:
            out += f", {g.ratio:.2f}x on the plain mean, {z_text(g.z)}"
        return out

    text = "; ".join(one(k, g) for k, g in r.groups.items())
    if legend:
        text += (
            f"; {Z_LEGEND}; a group is a misfit when z > {Z_MISFIT:g} and its error is more than "
            f"{RATIO_MISFIT}x its floor"
        )
    return text


def distribution_checks(cmp: Comparison | None) -> list[str]:
    """Distribution misfits of the ground-motion records, in words (empty when none is significant)."""
    out: list[str] = []
    if cmp is None or cmp.distribution is None or cmp.distribution.measured.size < 5:
        return out
    d = cmp.distribution
    if d.ks.pvalue < DIST_LEVEL:
        out.append(
            f"the theta_max/alpha distributions differ (Kolmogorov-Smirnov D = {d.ks.distance:.3f}, the "
            f"largest gap between the two cumulative distributions; p = {d.ks.pvalue:.2g})"
        )
    n = d.measured.size
    k1, k2 = int(np.isinf(d.measured).sum()), int(np.isinf(d.model).sum())
    pool = (k1 + k2) / (2 * n)
    if 0 < pool < 1:
        zz = (k2 - k1) / n / math.sqrt(2 * pool * (1 - pool) / n)
        if 2 * norm.sf(abs(zz)) < DIST_LEVEL:
            out.append(f"the overturn fractions differ (measured {k1}/{n}, model {k2}/{n}, z = {zz:+.1f})")
    return out


# ----------------------------------------------------------------------------
# the verdict
def pointer_text(classes: Sequence[PointerClass], model: Sequence[str] = ()) -> str:
    """Where to look first: the strongest physical class (:func:`physical_classes`) with two pieces of its
    evidence, then the others by name; ``""`` for none. The verdict's text ends with it.

    ``model``: the effects of the model the classes were drawn from (:func:`pointer_classes`); a class drawn
    from the plain model's localisation instead (``source`` ``"plain"``) says so.
    """
    if not classes:
        return ""
    top = classes[0]
    src, names = top.source, " + ".join(model)
    # whose values the evidence gives: the final model's, the plain model's, or (a drift, a probe) its own
    who = f"the model with {names}" if src == "final" and model else "the plain model" if src == "plain" else "model"
    ev = "; ".join(evidence_text(e, who) for e in top.evidence[:2])
    if src == "plain" and model:
        why = (
            f"Where to look first (what the plain model gets wrong, with the plain model's figures: the model "
            f"with {names} no longer departs here by more than 3 standard errors, so the added effect may cover "
            f"it in part): "
        )
    elif model:
        why = f"Where to look first, from what the model with {names} still gets wrong: "
    else:
        why = "Where to look first: "
    text = f"{why}{top.meaning} ({ev}; {Z_LOCAL_LEGEND})."
    if model and src != "plain":
        text += f" (These figures are with {names} in the model, which leaves this gap.)"
    if len(classes) > 1:
        text += " Then: " + "; ".join(c.name for c in classes[1:]) + "."
    return text


@dataclass(frozen=True)
class Verdict:
    """What the diagnosis can claim.

    Attributes
    ----------
    status : str
        One of :data:`housner.scenarios.diagnosis.verdict.status.STATUSES`.
    residual : Residual
        The final model's held-out error against its floor.
    baseline : Residual
        The plain model's.
    text : str
        One paragraph in words, opening with the status ("Explained: ..."): the JSON's; the command line and
        the report print it without that word, which their ``verdict:`` line and badge give.
    where : list of str
        Localisation items where the final model still differs from the measurement.
    next : list of PointerClass
        Physical classes to look at, strongest first (:func:`physical_classes`).
    distribution : list of str
        Distribution misfits of the final model.
    records_needed : int
        For ``inconclusive``: ground-motion records to add.
    """

    status: str
    residual: Residual
    baseline: Residual
    text: str
    where: list[str] = field(default_factory=list)
    next: list[PointerClass] = field(default_factory=list)
    distribution: list[str] = field(default_factory=list)
    records_needed: int = 0

    def to_dict(self) -> dict:
        r = self.residual
        return {
            "status": self.status,
            "residual": {"error": r.error, "floor": r.floor, "ratio": r.ratio, "z": r.z},
            "residual_detail": r.to_dict(),
            "baseline_residual": self.baseline.to_dict(),
            "text": self.text,
            "where": list(self.where),
            "next": [c.to_dict() for c in self.next],
            "distribution": list(self.distribution),
            "records_needed": self.records_needed,
        }

    @classmethod
    def from_dict(cls, data: dict) -> Verdict:
        """The verdict a diagnosis JSON holds (its ``residual`` is the head of ``residual_detail``)."""
        return cls(
            status=data["status"],
            residual=Residual.from_dict(data["residual_detail"]),
            baseline=Residual.from_dict(data["baseline_residual"]),
            text=data["text"],
            where=list(data["where"]),
            next=[PointerClass.from_dict(c) for c in data["next"]],
            distribution=list(data["distribution"]),
            records_needed=int(data["records_needed"]),
        )


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
    dist_plain, dist_final : list of str
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
    dist_plain: list[str]
    dist_final: list[str]
    plain_misfit: bool
    final_misfit: bool
    powered: bool
    probed: bool
    family_plain: str = ""
    search: str = "ran"

    @property
    def records_needed(self) -> int:
        """Ground-motion records to add for the power the verdict promises."""
        return self.final.records_needed if self.model else self.baseline.records_needed


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
    where = [evidence_text(ev) for c in final_classes for ev in c.evidence]
    if drift is not None:
        where = [evidence_text(ev) for ev in drift.evidence] + where
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
        verdict_text(facts, status),
        where,
        classes,
        facts.dist_final,
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
            label=f"a trial of physics outside the library (the probe {found.probe}: "
            + probe_words(found.probe)
            + "; "
            + ", ".join(f"{k} = {v:.3g}" for k, v in found.params.items())
            + "), fitted on top of the final model and held out as a candidate is: held-out error "
            + f"{found.error_with:.4g} alpha against {found.error:.4g} without it",
            measured=found.error_with,
            measured_se=found.se,
            model=found.error,
            model_se=0.0,
            z=found.z,
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


# ----------------------------------------------------------------------------
# the verdict in words
def verdict_text(facts: VerdictFacts, status: str) -> str:
    """The verdict's paragraph: the status in words with its figures (each statistic said once where it first
    appears), what is unusual and, for a misfit, where to look next."""
    text = _status_sentence(facts, status)
    if status in ("no_misfit", "explained"):
        local = facts.local_final if facts.model else facts.local_plain
        dist = facts.dist_final if facts.model else facts.dist_plain
        who = "the model with " + " + ".join(facts.model) if facts.model else "the plain model"
        bits = [evidence_text(e, who) for c in local for e in c.evidence[:1]] + dist
        if bits:
            text += (
                f" Unusual, though it does not make a misfit (the residual is at its floor): {'; '.join(bits)}"
                f" ({Z_LOCAL_LEGEND}). It says where a model with more physics would differ first, not that "
                "this one fails."
            )
    if status in ("partly_explained", "unexplained"):
        if facts.dist_final:
            text += " The distributions disagree too: " + "; ".join(facts.dist_final) + "."
        if facts.classes:
            text += " " + pointer_text(facts.classes, facts.model)
        else:
            text += (
                f" No localisation quantity differs by more than {Z_MISFIT:g} standard errors: the misfit is "
                "in the time histories only."
            )
    return text


def _figures(facts: VerdictFacts) -> tuple[str, str]:
    """The final and the plain model's figures: held-out error, floor (with the correct integrators it was
    measured over), residual ratio, by group. The plain model's come first in every paragraph: they say what
    the held-out error, the floor, the residual ratio and z are."""
    final, baseline = facts.final, facts.baseline
    fam_plain = facts.family_plain or facts.family
    fam = f"; correct models of the {family_text(fam_plain)}" if fam_plain else ""
    base_figs = (
        f"the plain Housner model's held-out error (each record predicted by the model fitted without it, mean "
        f"over the records) is {baseline.error:.4f} alpha against a correct-model floor of {baseline.floor:.4f} "
        f"alpha (the error a correct model leaves on these same records: their noise, and rocking's sensitivity "
        f"to small differences{fam}), residual ratio {baseline.ratio:.2f} (the worse group's error over its "
        f"floor; a correct model: 1; {_groups_text(baseline, legend=True)})"
    )
    # figs follow the fall's text ("... falls from 0.1752 to 0.0055 alpha"), which gives the final model's error
    figs = f"against its own correct-model floor of {final.floor:.4f} alpha"
    if facts.model:
        if facts.family and facts.family != fam_plain:
            figs += f" (correct models of the {family_text(facts.family)})"
        figs += f", residual ratio {final.ratio:.2f} ({_groups_text(final)})"
        figs += _floors_note(facts)
    return figs, base_figs


def _floors_note(facts: VerdictFacts) -> str:
    """Why the plain and the final model have two floors ('' when they have one)."""
    fam_plain = facts.family_plain or facts.family
    if facts.family and facts.family != fam_plain:
        return (
            f" (each model is judged against its own floor, measured over the narrowest family of correct "
            f"integrators whose floor its ground motions reach, the widest ('any') when they reach none: "
            f"'{fam_plain}' for the plain model, '{facts.family}' for this one; the plain model's floor is the "
            f"same whatever is added)"
        )
    if abs(facts.final.floor - facts.baseline.floor) > 1e-12:
        return (
            " (each model is judged against its own floor: a correct model of other physics leaves another "
            "error, as the records' chaos carries it elsewhere)"
        )
    return ""


def _effects_text(facts: VerdictFacts) -> str:
    """The final model's effects with their parameters as the final model holds them (fitted together)."""
    from housner.scenarios.diagnosis.results import params_text

    eff = " and ".join(f"{n} ({params_text(n, facts.params.get(n, {}))})" for n in facts.model)
    return eff + (", all parameters fitted together in the final model" if len(facts.model) > 1 else "")


def _fall_text(facts: VerdictFacts) -> str:
    """What the effects of the final model did to the held-out error ('' for the plain model)."""
    if not facts.model:
        return ""
    before, after = facts.baseline.error, facts.final.error
    change = "falls" if after < before else "rises"
    how = (
        "added by hand"
        if not facts.selected
        else "found by the search"
        if not facts.added
        else "added by hand and found"
    )
    return f"with {_effects_text(facts)} ({how}) the held-out error {change} from {before:.4f} to {after:.4f} alpha"


def _search_text(facts: VerdictFacts, other: bool) -> str:
    """What the search tried, exactly; ``other``: the final model holds effects already."""
    if facts.search == "ran" and facts.library:
        what = "none of the other effects" if other else "none of the effects"
        return f"{what} the search tried ({', '.join(facts.library)}) lowers it significantly"
    if facts.search == "skipped":
        return (
            "the search tried no effect: the training error was already within a tenth of the sensor noise "
            "of the error the noise alone leaves, so nothing was left for an effect to take"
        )
    if facts.search == "none_left":
        return (
            "the search tried no effect: no candidate was left to try (--max-effects 0, or each candidate "
            "already in the model or incompatible with it)"
        )
    return "no library search ran (no candidate effects were given: --effects none, or effects=[])" + (
        "; only the effects added by hand were tried" if other else ", and no effect was added by hand"
    )


def _status_sentence(facts: VerdictFacts, status: str) -> str:
    """The status in words, with the figures it rests on."""
    figs, base_figs = _figures(facts)
    if status == "inconclusive" and facts.n_records < MIN_RECORDS:
        return (
            f"Inconclusive: {facts.n_records} usable records are too few to tell a misfit from chance (at least "
            f"{MIN_RECORDS} are needed, with free vibrations among them); {base_figs}."
        )
    if not facts.model and not facts.plain_misfit:
        return _unless_underpowered(
            facts.powered,
            f"No misfit: {base_figs}; no group is more than {RATIO_MISFIT}x above it with significance, which is "
            f"what a correct model shows on these records. No effect is needed. This campaign would have detected "
            f"a misfit of {facts.final.detectable_ratio:.2f}x the floor or more.",
            f"Inconclusive: {base_figs}, not significantly above it, but with these records only a misfit of "
            f"{facts.final.detectable_ratio:.2f}x the floor or more would show; about {facts.records_needed} more "
            f"ground-motion records are needed to see one of {DETECTABLE_RATIO}x.",
        )
    if not facts.model:
        return f"Unexplained: {base_figs}: a misfit; {_search_text(facts, other=False)}."
    if not facts.final_misfit:
        return _explained_sentence(facts, figs, base_figs)
    return _partly_explained_sentence(facts, figs, base_figs)


def _explained_sentence(facts: VerdictFacts, figs: str, base_figs: str) -> str:
    """The verdict of a final model at its floor (``explained``, or ``inconclusive`` when underpowered)."""
    final, fall = facts.final, _fall_text(facts)
    small = (
        ""
        if facts.plain_misfit
        else (
            " The plain model was already within the floor's band, yet the fall is "
            "significant on the held-out records: a small effect that many records prove."
        )
    )
    doubt = (
        ""
        if final.ratio <= RATIO_MISFIT
        else (
            f" Its residual ratio {final.ratio:.2f} lies above the {RATIO_MISFIT}x band, but not significantly "
            f"({z_text(final.z)} <= {Z_MISFIT:g}): these records cannot tell it from the floor."
        )
    )
    return _unless_underpowered(
        facts.powered,
        f"Explained: {base_figs}; {fall}, {figs}: no group more than {RATIO_MISFIT}x above its floor with "
        f"significance, what a correct model shows. {' + '.join(facts.model)} explains it.{small}{doubt}",
        f"Inconclusive: {base_figs}; {fall}, {figs}, but these records would only show a remaining misfit "
        f"of {final.detectable_ratio:.2f}x or more; about {facts.records_needed} more ground-motion records are "
        "needed.",
    )


def _partly_explained_sentence(facts: VerdictFacts, figs: str, base_figs: str) -> str:
    """The verdict of a final model still above its floor."""
    fall = _fall_text(facts)
    searched = _search_text(facts, other=True)
    if facts.final.misfit or not (facts.drift or facts.probed or facts.local_final):
        return (
            f"Partly explained: {base_figs}; {fall}, {figs}. A misfit of {facts.final.ratio:.2f}x the floor "
            f"(the worse group of records) remains; {searched}."
        )
    probed = [c for c in facts.classes if any(e.is_probe for e in c.evidence)]
    who = "the model with " + " + ".join(facts.model)
    ev = "; ".join(
        evidence_text(e, who)
        for c in ([facts.drift] if facts.drift else []) + probed + facts.local_final
        for e in c.evidence[:2]
    )
    return (
        f"Partly explained: {base_figs}; {fall}, {figs}: above the floor's {RATIO_MISFIT}x band, "
        f"and the recording order, a probe of physics outside the library or the localisation (beyond "
        f"{Z_LOCAL:g} standard errors) still points to a misfit ({ev}; {Z_LOCAL_LEGEND}); {searched}."
    )


def _unless_underpowered(powered: bool, text: str, weak: str) -> str:
    """``text`` when the records have the power the verdict promises (a misfit of :data:`DETECTABLE_RATIO` x the
    floor would show), else ``weak``, which says so (the status is then ``inconclusive``: :func:`status_rule`)."""
    return text if powered else weak
