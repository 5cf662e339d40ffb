"""A diagnosis' numbers in words: errors with their standard errors, fitted parameters with their units, z-scores,
evidence and the floors' families, said so that a reader needs nothing else
(:mod:`housner.reports.diagnosis.verdict_text` writes the verdict's paragraph with them)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from housner.effects import effect_class

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.comparison.pointers import Evidence

__all__ = [
    "Z_LEGEND",
    "Z_LOCAL_LEGEND",
    "Z_SHOWN",
    "at_bound",
    "change_text",
    "evidence_text",
    "family_text",
    "fmt_pm",
    "g4",
    "param_unit",
    "probe_label",
    "probe_words",
    "params_text",
    "step_params",
    "z_text",
]

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
    try:
        return effect_class(name).probe_summary or name
    except (KeyError, ValueError):
        return name


def probe_label(ev: Evidence) -> str:
    """A probe's figure in words: what it adds, its fitted parameters and the held-out errors with and without it."""
    name = ev.metric.removeprefix("probe:")
    params = ", ".join(f"{k} = {v:.3g}" for k, v in ev.params.items())
    return (
        f"a trial of physics outside the library (the probe {name}: {probe_words(name)}; {params}), fitted on top "
        f"of the final model and held out as a candidate is: held-out error {ev.measured:.4g} alpha against "
        f"{ev.model:.4g} without it"
    )


def evidence_text(ev: Evidence, model: str = "model") -> str:
    """One piece of a pointer's evidence in words: the measured value, the model's (named ``model``) and z."""
    if ev.is_probe:
        return f"{probe_label(ev)} ({z_text(ev.z)}: the fall in standard errors of the paired differences)"
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


# ----------------------------------------------------------------------------
# numbers in words
def fmt_pm(value, se, *, sep: str = " +- ", inf: str = "overturned", nan: str = "n/a") -> str:
    """A value with its standard error: the error to 2 significant digits, the value to the same decimal place.

    ``fmt_pm(0.0031234, 0.000423)`` is ``"0.00312 +- 0.00042"``, ``fmt_pm(123.4, 15.6)`` is ``"123 +- 16"``.
    An infinite value (a theta_max/alpha of an overturned block) is written ``inf`` (``"overturned"``, or
    ``"-inf"`` when negative) without an uncertainty; a missing value is ``nan``; a value whose
    standard error is missing or infinite is written to 4 significant digits alone, and one with a
    zero standard error to 4 significant digits ``+- 0``.

    Parameters
    ----------
    value, se : float
    sep : str
        Between the two (``" &plusmn; "`` on an HTML page).
    inf, nan : str
        What an infinite and a missing value read as.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        return nan
    if math.isnan(v):
        return nan
    if math.isinf(v):
        return inf if v > 0 else "-inf"
    try:
        e = abs(float(se))
    except (TypeError, ValueError):
        e = math.nan
    if not math.isfinite(e):
        return _sig(v, 4)
    if e == 0.0:
        return f"{_sig(v, 4)}{sep}0"
    decimals = 1 - math.floor(math.log10(e))  # 2 significant digits of the error
    if math.floor(math.log10(round(e, decimals))) > math.floor(math.log10(e)):  # 0.000996 -> 0.0010
        decimals -= 1
    if decimals > 12:  # too small for fixed notation to stay readable
        return f"{v:.3e}{sep}{e:.1e}"
    return f"{_fixed(v, decimals)}{sep}{_fixed(e, decimals)}"


def _fixed(v: float, decimals: int) -> str:
    r = round(v, decimals)
    if r == 0:
        r = 0.0  # no "-0.000"
    return f"{r:.{max(decimals, 0)}f}"


def _sig(v: float, digits: int) -> str:
    """``v`` to ``digits`` significant digits in fixed notation where that stays short."""
    if v == 0:
        return "0"
    if not 1e-4 <= abs(v) < 1e6:
        return f"{v:.{digits - 1}e}"
    return _fixed(v, max(digits - 1 - math.floor(math.log10(abs(v))), 0))


def change_text(improvement: float, se: float, *, sep: str = " +- ") -> str:
    """A paired improvement (previous error minus this one) in words: ``"falls by X +- s"`` or ``"rises by X +- s"``.

    The figure is always positive: an error that grows "rises by 0.05", never "falls by -0.05".
    """
    try:
        d = float(improvement)
    except (TypeError, ValueError):
        d = math.nan
    if not math.isfinite(d):
        return "does not change measurably"
    return f"{'falls' if d >= 0 else 'rises'} by {fmt_pm(abs(d), se, sep=sep)}"


def param_unit(name: str, key: str) -> str:
    """The unit of parameter ``key`` of effect ``name`` (its ParamSpec's), "" when unknown."""
    try:
        return effect_class(name).param_specs[key].unit
    except (KeyError, ValueError, AttributeError):
        return ""


def step_params(name: str, params: dict, final: dict | None) -> str:
    """An effect's parameters as fitted at its step of the ladder; where the final model's joint refit moved
    them, both, each labelled (the verdict's text gives the final model's)."""
    text = params_text(name, params)
    if final is None or params_text(name, final) == text:
        return text
    return (
        f"{text} as fitted at this step; {params_text(name, final)} in the final model, refitted with the "
        "effects after it"
    )


def params_text(name: str, params: dict, *, digits: int = 4) -> str:
    """``"c = 0.5999 1/s"``: an effect's fitted parameters with their units ([-] when dimensionless), and where
    one stopped at an end of its search range that is not its neutral value, that it did (:func:`at_bound`)."""
    out = []
    for k, v in params.items():
        unit = param_unit(name, k)
        unit = "[-]" if unit in ("-", "") else unit
        out.append(f"{k} = {_sig(float(v), digits) if math.isfinite(float(v)) else v} {unit}{at_bound(name, k, v)}")
    return ", ".join(out)


def at_bound(name: str, key: str, value) -> str:
    """``" (at the top of its search range 0-0.5: the fit may want a larger value ...)"``, or ``""``.

    A parameter fitted to within 1e-6 of the range's span from an end that is not its neutral value (0 damping
    at the bottom is a fit that found no effect, not a range too narrow) may be held back by the range: an
    effect that fails so is not shown to be wrong. Ranges that depend on the specimen are not checked here.
    """
    from housner.scenarios.diagnosis.selection.fitting import search_bounds

    try:
        bounds = search_bounds(name, key)
        neutral = effect_class(name).param_specs[key].neutral_for(None)
        v = float(value)
    except (KeyError, ValueError, TypeError, AttributeError):
        return ""
    if bounds is None or not math.isfinite(v):
        return ""
    lo, hi = float(bounds[0]), float(bounds[1])
    near = 1e-6 * (hi - lo)
    for end, word, more in ((hi, "top", "larger"), (lo, "bottom", "smaller")):
        if math.isfinite(end) and abs(v - end) <= near and end != neutral:
            return (
                f" (at the {word} of its search range {lo:g} to {hi:g}: the fit may want a {more} value, so this "
                "fit does not rule the effect out; widen its bounds to test it)"
            )
    return ""
