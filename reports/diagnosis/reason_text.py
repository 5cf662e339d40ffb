"""A candidate's reason in words (:class:`housner.scenarios.diagnosis.selection.reasons.Reason`): as the diagnosis
JSON keeps it, with its changes signed (``falls by -0.0012``), and as the report and the summary say it
(``rises by 0.0012``)."""

from __future__ import annotations

from housner.scenarios.diagnosis.selection.reasons import Reason

__all__ = ["reason_text", "reason_words"]

_NOISE = "a tenth of the sensor noise"


def _falls(x: float, signed: bool) -> str:
    """ "falls by" a signed change ("falls by -0.0012"), or in words "rises by 0.0012"."""
    s = f"{x:+.4f}"
    if signed:
        return f"falls by {s}"
    return f"{'rises' if s[0] == '-' else 'falls'} by {s[1:]}"


def _lowers_on(x: float, on: str, signed: bool) -> str:
    """ "lowers the error on ``on`` by" a signed change, or in words "raises ... by" a negative one."""
    s = f"{x:+.4f}"
    if signed:
        return f"lowers the error on {on} by {s}"
    return f"{'raises' if s[0] == '-' else 'lowers'} the error on {on} by {s[1:]}"


def _text(r: Reason, signed: bool) -> str:
    f, k = r.figures, r.kind
    if k == "changes_nothing":
        return "changes nothing"
    if k == "no_improvement":
        return "no improvement"
    if k == "within_uncertainty":
        return f"within its uncertainty (p = {f['p']:.2g} > {f['level']:.2g})"
    if k == "below_practical":
        return f"below a tenth of the sensor noise ({f['fall']:.4f} < {f['need']:.4f} alpha)"
    if k == "significant":
        return f"p = {f['p']:.2g} <= {f['level']:.2g} and {f['fall']:.4f} >= {f['need']:.4f} alpha"
    if k == "rejected_not_finite":
        return f"rejected: its theta history is not finite on record {f['record']!r} (no score is made of NaN)"
    if k == "training_fall_small":
        return f"training error {_falls(f['fall'], signed)} < {f['margin']:.4f} alpha ({_NOISE}): not held out"
    if k == "fitted_fall_small":
        return (
            f"even on the records it was fitted to, the mean error per record {_falls(f['fall'], signed)} < "
            f"{f['margin']:.4f} alpha ({_NOISE}): not held out"
        )
    if k == "fitted_within_uncertainty":
        return (
            f"even on the records it was fitted to, its fall is within its uncertainty (p = {f['p']:.2g} > "
            f"{f['level']}): not held out"
        )
    if k == "grid_fall_small":
        return (
            f"error on {f['records']} records {_falls(f['fall'], signed)} < {f['margin']:.4f} alpha "
            f"({_NOISE}): not fitted further"
        )
    if k == "subset_fall_small":
        on = "all records" if f["records"] == 0 else f"the {f['records']} records it is fitted on"
        return (
            f"the subset's best point {_lowers_on(f['fall'], on, signed)} < {f['margin']:.4f} alpha ({_NOISE}): "
            "not fitted further"
        )
    if k == "free_vibrations":
        return (
            f"contradicts the free vibrations: {f['quantity']} is {f['z']:+.1f} standard errors from the measured "
            f"{f['measured']:.4g} +- {f['se']:.2g}"
        )
    if k == "at_neutral":
        said = "; ".join(f"{key} = {x:.4g} +- {se:.2g} (neutral {n:.4g})" for key, x, n, se in f["params"])
        return (
            f"at its neutral value within its uncertainty ({said}; the folds' jackknife): the plain model, so "
            f"its fall of {f['fall']:+.4f} alpha is the fit moving within its noise, not evidence of the effect"
        )
    if k == "kernel_numerics":
        faded = ", ".join(f"{key}={v:.4g}" for key, v in f["faded"].items())
        return (
            f"its kernel's numerics, not its physics: the same kernel with {f['effect']} faded out ({faded}) does "
            f"as well (p = {f['p']:.2g})"
        )
    if k == "at_noise":
        return (
            f"the training error {f['train']:.4f} alpha is within {f['margin']:.4f} of the sensor noise "
            f"({f['noise']:.4f}): nothing is left for an effect to lower by a tenth of the noise; not searched"
        )
    raise ValueError(f"no words for reason {k!r}")


def reason_text(r: Reason | None) -> str:
    """The reason as the diagnosis JSON keeps it ('' for none): changes with their sign."""
    return "" if r is None else _text(r, signed=True)


def reason_words(r: Reason | None) -> str:
    """The reason as the report and the summary say it ('' for none): a negative fall said as a rise."""
    return "" if r is None else _text(r, signed=False)
