"""The diagnosis' verdict in words: its z-scores, its evidence and the floors' families, said so that a reader needs
nothing else (:mod:`housner.scenarios.diagnosis.verdict.decision` writes the paragraph with them)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.comparison.pointers import Evidence

__all__ = ["Z_LEGEND", "Z_LOCAL_LEGEND", "Z_SHOWN", "evidence_text", "family_text", "g4", "probe_words", "z_text"]

#: Beyond this |z| the text says "z > 100": more digits say nothing more about a misfit [-].
Z_SHOWN = 100.0
#: The residual's z, said once where it first appears in the verdict.
Z_LEGEND = (
    "z: the held-out error's excess over the floor, record by record, in standard errors of that excess; "
    "about 0 for a correct model"
)
#: The localisation's z, said once where the pointer first gives one.
Z_LOCAL_LEGEND = (
    "z: how many standard errors of their difference separate the model's value from the measured "
    "one; beyond 3 it points here"
)


def z_text(z: float) -> str:
    """``z = +2.9``, or ``z > 100`` where more digits say nothing more."""
    if math.isfinite(z) and abs(z) < Z_SHOWN:
        return f"z = {z:+.1f}"
    return f"z > {Z_SHOWN:g}" if z > 0 else f"z < -{Z_SHOWN:g}"


def probe_words(name: str) -> str:
    """What a probe (:mod:`housner.scenarios.diagnosis.selection.probes`) adds, in words: its ``probe_summary``
    (its name where it declares none)."""
    from housner.effects import effect_class

    try:
        return effect_class(name).probe_summary or name
    except (KeyError, ValueError):
        return name


def evidence_text(ev: Evidence, model: str = "model") -> str:
    """One piece of a pointer's evidence in words: the measured value, the model's (named ``model``) and z."""
    if ev.is_probe:
        return f"{ev.label} ({z_text(ev.z)}: the fall in standard errors of the paired differences)"
    return (
        f"{ev.label}: measured {g4(ev.measured)} +- {g4(ev.measured_se)}, {model} {g4(ev.model)} "
        f"+- {g4(ev.model_se)} ({z_text(ev.z)})"
    )


def family_text(family: str) -> str:
    """The correct integrators a floor was measured over, in words
    (:data:`housner.scenarios.diagnosis.verdict.integrator_families.
    FAMILIES`)."""
    words = {
        "exact": "integrated as this library integrates, with the table acceleration's measured noise",
        "solver": "another integrator step and rest rule on the same table motion",
        "any": "any integrator step and rest rule, and the table motion's timing and scale anywhere in their "
        "uncertainty (up to half a sample; about 0.1 %), held or linear between samples",
    }
    if family.startswith("input-"):
        share = family.split("-", 1)[1]
        return (
            f"family '{family}': another integrator step and rest rule, and the table motion's timing and "
            f"scale within {share} of their uncertainty"
        )
    return f"family '{family}': {words[family]}" if family in words else f"family '{family}'"


def g4(v: float) -> str:
    return f"{v:.4g}" if math.isfinite(v) else str(v)
