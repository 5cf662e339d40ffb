"""What a diagnosis should say of a synthetic campaign, shared by the matrix tests and scripts/diagnosis_matrix.py."""

from __future__ import annotations

#: A control's residual ratio may not exceed this [-] (the verdict's own RATIO_MISFIT).
CONTROL_RATIO = 1.25


def judge(expected, diag, faults: tuple[str, ...] | None = None) -> tuple[bool, str]:
    """Whether ``diag`` is right for ``expected``, and why not ('' when it is).

    ``expected`` is () for a control (``no_misfit``, ratio <= 1.25), a tuple of registry names for
    library effects (``explained``, naming exactly those), or the class that should come first for an
    effect outside the library (``partly_explained`` or ``unexplained``). ``faults``: the sensor faults
    the assessment must name, exactly (None: not checked).
    """
    if faults is not None:
        sensor = getattr(diag.campaign, "sensor", None)
        named = set(sensor.fault_kinds) if sensor is not None else set()
        if named != set(faults):
            return False, f"sensor faults {sorted(named)} (expected {sorted(faults)})"
    v = diag.verdict
    if isinstance(expected, str):
        first = v.next[0].name if v.next else "none"
        ok = v.status in ("partly_explained", "unexplained") and first == expected
        return ok, "" if ok else f"status {v.status}, first class {first} (expected {expected})"
    if not expected:
        ok = v.status == "no_misfit" and v.residual.ratio <= CONTROL_RATIO
        return ok, "" if ok else f"status {v.status}, ratio {v.residual.ratio:.2f}"
    named = set(diag.selected) | set(diag.added)
    ok = v.status == "explained" and named == set(expected)
    return ok, "" if ok else f"status {v.status}, named {sorted(named)} (expected {sorted(expected)})"
