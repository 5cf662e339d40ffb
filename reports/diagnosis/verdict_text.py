"""A diagnosis in words: the verdict's paragraph, drawn from its facts, and the one-paragraph summary that the
command line prints and the JSON keeps (:mod:`housner.reports.diagnosis.words` says the numbers)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from housner.reports.diagnosis.reason_text import reason_words
from housner.reports.diagnosis.sensor_text import noise_text, sensor_verdict_sentence
from housner.reports.diagnosis.words import (
    Z_LEGEND,
    Z_LOCAL_LEGEND,
    change_text,
    evidence_text,
    family_text,
    fmt_pm,
    params_text,
    step_params,
    z_text,
)
from housner.scenarios.diagnosis.comparison.pointers import MIN_RECORDS, PointerClass
from housner.scenarios.diagnosis.economies import (
    Economy,
    FloorLoopStopped,
    MechanicsSubset,
    ThinnedSearch,
)
from housner.scenarios.diagnosis.verdict.decision import Z_LOCAL, DistributionMisfit, Verdict, VerdictFacts
from housner.scenarios.diagnosis.verdict.residual_test import (
    DETECTABLE_RATIO,
    RATIO_MISFIT,
    Z_MISFIT,
    GroupResidual,
    Residual,
)

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.results import Diagnosis

__all__ = [
    "diagnosis_summary",
    "distribution_text",
    "economy_text",
    "pointer_text",
    "said_distributions",
    "verdict_paragraph",
    "verdict_text",
    "where_texts",
]


def verdict_paragraph(diag: Diagnosis, *, pointer: bool = True) -> str:
    """The verdict's paragraph as the JSON and the command line give it: its text (:func:`verdict_text`), then what
    the sensor's assessment says and how the figures were computed (what ran on fewer samples or stopped early).
    ``""`` without a verdict."""
    v = diag.verdict
    if v is None:
        return ""
    text = verdict_text(v.facts, v.status, pointer=pointer)
    sensor = getattr(diag.campaign, "sensor", None)
    if sensor is not None:
        text += sensor_verdict_sentence(sensor)
    if diag.settings.economies:
        text += " How it was computed: " + " ".join(economy_text(e) for e in diag.settings.economies)
    return text


def economy_text(e: Economy) -> str:
    """What a diagnosis computed on fewer samples or stopped early
    (:mod:`housner.scenarios.diagnosis.economies`), in words."""
    if isinstance(e, FloorLoopStopped):
        who, first, last = f"the {e.model} model", e.families[0], e.families[-1]
        if e.said_before:
            return (
                f"The floor's family loop stopped early for {who} too: {e.ratio:.2f}x under {first!r}, "
                f"{e.widest_ratio:.2f}x under {last!r}."
            )
        between = ", ".join(repr(f) for f in e.families[1:-1])
        return (
            f"The floor's family loop stopped early: {who}'s ground motions are {e.ratio:.2f}x their floor under the "
            f"narrowest family ({first!r}, more than {e.jump:g} x {e.band:g}) and {e.widest_ratio:.2f}x it under the "
            f"widest ({last!r}, not at it either), so the families between ({between}) were not measured: nested, "
            "their floors lie below the widest's."
        )
    if isinstance(e, MechanicsSubset):
        return (
            f"Models with an effect that replaces the equation of motion (its kernel 10-100x slower) were fitted on "
            f"the free vibrations and {e.fitted} of the {e.ground_motions} ground motions, spread over the campaign "
            f"({e.fitted_s:.0f} of {e.total_s:.0f} s of error windows; their grids on {e.grid_records} records); "
            "their training errors, screens, held-out errors and tests are on every record."
        )
    if isinstance(e, ThinnedSearch):
        low, high = e.rates[0], e.rates[-1]
        rate = f"{low:g} Hz" if len(e.rates) == 1 else f"{low:g}-{high:g} Hz"
        return (
            f"The search ran on every {e.decimation}th sample ({rate} thinned to {low / e.decimation:g} Hz; "
            f"{e.search_rate:g} Hz is what the physics needs: the fits' ranges are set for it, the fastest, a 100 Hz "
            "foundation, has 5 samples a period): theta as sampled (its noise stays white of the same sigma, so a "
            "record's error is the same mean over fewer samples), the table acceleration through an anti-alias filter "
            "(zero-phase, below the new Nyquist frequency). The candidates' fits, held-out errors and tests, the pairs "
            "and the probes are on those samples; the ladder's errors, the floors and the verdict on every sample."
        )
    return (
        f"On every sample the fall of step {e.step} (+ {e.added}) is {e.improvement:+.4f} +- "
        f"{e.improvement_se:.4f} alpha, p = {e.pvalue:.2g}: not significant at its round's level "
        f"{e.level:.2g}, as it was on every {e.decimation}th sample; it stays in the ladder."
    )


def where_texts(verdict: Verdict) -> list[str]:
    """The localisation quantities where the final model still differs from the measurement, in words."""
    return [evidence_text(ev) for ev in verdict.where]


def distribution_text(d: DistributionMisfit) -> str:
    """A distribution misfit (:func:`housner.scenarios.diagnosis.verdict.decision.distribution_checks`) in words."""
    if d.kind == "ks":
        return (
            f"the theta_max/alpha distributions differ (Kolmogorov-Smirnov D = {d.distance:.3f}, the "
            f"largest gap between the two cumulative distributions; p = {d.pvalue:.2g})"
        )
    return f"the overturn fractions differ (measured {d.measured}/{d.n}, model {d.model}/{d.n}, z = {d.z:+.1f})"


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


def said_distributions(facts: VerdictFacts, status: str) -> list[DistributionMisfit]:
    """The distribution misfits the verdict's paragraph gives (:func:`verdict_text`): the final model's for a
    misfit, the judged model's as unusual at the floor, none otherwise."""
    if status in ("partly_explained", "unexplained"):
        return list(facts.dist_final)
    if status in ("no_misfit", "explained"):
        return list(facts.dist_final if facts.model else facts.dist_plain)
    return []


def verdict_text(facts: VerdictFacts, status: str, *, pointer: bool = True) -> str:
    """The verdict's paragraph: the status in words with its figures (each statistic said once where it first
    appears), what is unusual and, for a misfit, where to look next (``pointer`` False: a reference to the list
    of classes that a page gives under it instead)."""
    text = _status_sentence(facts, status)
    if status in ("no_misfit", "explained"):
        local = facts.local_final if facts.model else facts.local_plain
        who = "the model with " + " + ".join(facts.model) if facts.model else "the plain model"
        bits = [evidence_text(e, who) for c in local for e in c.evidence[:1]]
        bits += [distribution_text(d) for d in said_distributions(facts, status)]
        if bits:
            text += (
                f" Unusual, though it does not make a misfit (the residual is at its floor): {'; '.join(bits)}"
                f" ({Z_LOCAL_LEGEND}). It says where a model with more physics would differ first, not that "
                "this one fails."
            )
    if status in ("partly_explained", "unexplained"):
        if facts.dist_final:
            dist = said_distributions(facts, status)
            text += " The distributions disagree too: " + "; ".join(distribution_text(d) for d in dist) + "."
        if facts.classes:
            text += " " + (
                pointer_text(facts.classes, facts.model) if pointer else "Where to look: see the list below."
            )
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


def diagnosis_summary(diag: Diagnosis) -> str:
    """One paragraph: the verdict in words, then the ladder with its figures.

    Every error is in units of alpha with its standard error (:func:`fmt_pm`); a change is said as
    "falls by" or "rises by" with a positive figure, and a parameter carries its unit.
    """
    parts = [verdict_paragraph(diag)]
    chosen = diag.steps[1:]
    if chosen:
        ladder = []
        final_params = dict(diag.steps[-1].effects)
        for st in chosen:
            prm = "; ".join(step_params(n, dict(st.effects)[n], final_params.get(n)) for n in st.added_effects)
            how = " (by hand)" if st.by_hand else ""
            ladder.append(
                f"+ {st.added}{how} ({prm}): held-out error {fmt_pm(st.heldout_error, st.heldout_se)} alpha, "
                f"which {change_text(st.improvement, st.improvement_se)} alpha"
                f"{'' if st.significant else ', not significant'}"
            )
        parts.append("Ladder: " + "; ".join(ladder) + ".")
        b, f = diag.baseline, diag.final
        verb = "falls" if diag.reduction >= 0 else "rises"
        parts.append(
            f"In all the held-out error {verb} by {abs(100 * diag.reduction):.0f} %, from "
            f"{fmt_pm(b.heldout_error, b.heldout_se)} to {fmt_pm(f.heldout_error, f.heldout_se)} alpha."
        )
    elif diag.candidates:
        best = diag.candidates[0]
        if math.isfinite(best.improvement):
            verb = "lower" if best.improvement >= 0 else "raise"
            parts.append(
                f"The best candidate, {best.effect}, would {verb} the held-out error by "
                f"{fmt_pm(abs(best.improvement), best.improvement_se)} alpha ({reason_words(best.reason)})."
            )
    sensor = getattr(diag.campaign, "sensor", None)
    if sensor is not None and sensor.noise.white and not sensor.faults:
        parts.append(f"Sensor noise: {noise_text(sensor.noise)}.")  # else the verdict's text says it
    k = diag.settings.folds
    parts.append(
        f"({k}-fold cross-validation: every record held out once; sensor noise sigma/alpha {diag.noise_floor:.2g}.)"
    )
    return " ".join(p for p in parts if p)
