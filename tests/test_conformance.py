"""Every registered engine passes the conformance check; the check itself catches broken engines."""

from __future__ import annotations

import importlib
import math
from dataclasses import replace

import numpy as np
import pytest

from housner import EngineError, Specimen
from housner.engines import ENGINES, Engine
from housner.engines.base import engine_class
from housner.engines.conformance import ConformanceReport, assert_conforms, check_engine
from housner.model import simulate as housner_simulate

SEED = Specimen.bachmann2017()


def _importable(name: str) -> str | None:
    """None if the engine's class imports, else the reason it does not (for a skip)."""
    entry = ENGINES[name].entry_point
    if isinstance(entry, str):
        module = entry.partition(":")[0]
        try:
            importlib.import_module(module)
        except ImportError as e:  # an engine still being written
            return f"engine {name!r}: module {module} does not import yet ({e})"
    try:
        engine_class(name)()
    except EngineError as e:  # an optional engine whose package is not installed
        return str(e)
    return None


def _planar_engines() -> list[str]:
    """The registered engines that take a planar block (the conformance checks drive the seed specimen); the 3D
    scan-mesh engines (``mesh_engine``) need a mesh and are checked in tests/test_mesh_engines.py."""
    out = []
    for name in sorted(ENGINES):
        try:
            cls = ENGINES[name].load()
        except ImportError:  # not installed: listed, and skipped by the test with its reason
            out.append(name)
            continue
        if not getattr(cls, "mesh_engine", False):
            out.append(name)
    return out


@pytest.mark.parametrize("name", _planar_engines(), ids=str)
def test_registered_engine_conforms(name):
    reason = _importable(name)
    if reason:
        pytest.skip(reason)
    report = assert_conforms(name)  # raises AssertionError with the list of failures
    assert report.ok and {c.name for c in report.checks} == {
        "at_rest",
        "mirror_symmetry",
        "deterministic",
        "sign_and_overturn",
        "free_vibration_period",
        "finite_and_bounded",
    }
    assert engine_class(name).name == name


# --------------------------------------------------------------------------- the check can fail
class _Analytic(Engine):
    """The analytic model with a deliberate defect, to show that each check can fail."""

    name = "broken"

    def __init__(self, defect: str):
        self.defect = defect
        self.calls = 0

    def _simulate(self, specimen, motion, effects):
        self.calls += 1
        if self.defect == "wrong_p":  # a block with 3 % too high p
            resp = housner_simulate(specimen.with_p(1.03 * specimen.p), motion)
            return replace(resp, alpha=specimen.alpha)
        resp = housner_simulate(specimen, motion)
        if self.defect == "flipped":  # theta of the wrong sign
            return replace(resp, theta=-resp.theta, theta_dot=-resp.theta_dot)
        upright = np.abs(resp.theta) < math.pi / 2  # leave an overturn at +-pi/2 alone
        if self.defect == "drifting":  # a different result on every call
            return replace(resp, theta=np.where(upright, resp.theta + 1e-9 * self.calls, resp.theta))
        if self.defect == "creeping":  # tilts a little under any load
            tilt = 2e-3 * specimen.alpha * np.tanh(motion.acc / specimen.uplift_acceleration)
            return replace(resp, theta=np.where(resp.theta == 0.0, -tilt, resp.theta))
        if self.defect == "lopsided":  # rocks 5 % further toward +x
            return replace(resp, theta=np.where((resp.theta > 0) & (resp.theta < 1.0), 1.05 * resp.theta, resp.theta))
        if self.defect == "unbounded":  # falls past pi/2
            return replace(resp, theta=np.where(np.abs(resp.theta) >= math.pi / 2, 1.01 * resp.theta, resp.theta))
        raise AssertionError(self.defect)


@pytest.mark.parametrize(
    ("defect", "failed"),
    [
        ("wrong_p", {"free_vibration_period"}),
        ("flipped", {"sign_and_overturn"}),
        ("drifting", {"deterministic"}),
        ("creeping", {"at_rest"}),
        ("lopsided", {"mirror_symmetry"}),
        ("unbounded", {"finite_and_bounded", "sign_and_overturn"}),
    ],
)
def test_check_catches_a_broken_engine(defect, failed):
    report = check_engine(_Analytic(defect), SEED)
    assert not report.ok
    assert {c.name for c in report.checks if not c.passed} == failed
    with pytest.raises(AssertionError, match="fails .* conformance check") as info:
        report.assert_ok()
    for name in failed:
        assert name in str(info.value)


def test_report_reads_well():
    report = check_engine("housner")
    assert isinstance(report, ConformanceReport) and report.ok and report.failures == []
    text = str(report)
    assert text.startswith("conformance of HousnerEngine") and "[ok] free_vibration_period" in text
    period = next(c for c in report.checks if c.name == "free_vibration_period")
    assert period.value < 1e-6  # the analytic model against the exact quadrature
