"""The engine registry: one EngineSpec per engine, each fact declared once, read without importing the engine."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import pytest

from housner.engines import ENGINES, Engine, EngineSpec, engine_class, get_engine, register_engine
from housner.engines.analytic import HousnerEngine
from housner.engines.base import SpecAttribute

SHIPPED = ("housner", "mujoco", "pybullet", "dart", "opensees", "drake")


def test_the_shipped_engines_are_specs_named_by_module_and_class():
    assert tuple(ENGINES)[: len(SHIPPED)] == SHIPPED
    for name in SHIPPED:
        spec = ENGINES[name]
        assert isinstance(spec, EngineSpec) and spec.name == name
        assert isinstance(spec.entry_point, str) and spec.module.startswith("housner.engines.")
        assert spec.distribution and spec.label
    assert ENGINES["dart"].distribution == "dartpy" and "pip install" in ENGINES["dart"].install
    with pytest.raises(dataclasses.FrozenInstanceError):
        ENGINES["dart"].distribution = "other"


def test_a_class_reads_its_facts_from_its_spec():
    """The distribution, install hint and label are declared on the spec only; the class reads them."""
    pybullet = engine_class("pybullet")
    assert pybullet.package == "pybullet" and pybullet.LABEL == "PyBullet"
    assert engine_class("opensees").INSTALL == ENGINES["opensees"].install
    assert isinstance(Engine.__dict__["package"], SpecAttribute)
    assert Engine.package == ""  # not registered


def test_listing_the_engines_imports_none():
    code = (
        "import sys\nfrom housner.cli import main\nmain(['--version'])\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('mujoco', 'pybullet', 'dartpy', 'pydrake')))"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    versions, imported = res.stdout.splitlines()
    assert imported == "[]" and all(f"{n} " in versions for n in SHIPPED)


def test_register_engine_by_entry_point_and_by_decorator():
    try:
        spec = register_engine("lazy-mine", "no_such_package.engine:Mine", distribution="no-such-dist", label="Mine")
        assert ENGINES["lazy-mine"] is spec and spec.module == "no_such_package.engine" and spec.install == ""
        with pytest.raises(ModuleNotFoundError):
            engine_class("lazy-mine")

        @register_engine("decorated-mine")
        class Mine(HousnerEngine):
            package = "my-solver"

        assert Mine.name == "decorated-mine" and engine_class("decorated-mine") is Mine
        assert (
            ENGINES["decorated-mine"].distribution == "my-solver"
            and ENGINES["decorated-mine"].label == "decorated-mine"
        )
        assert isinstance(get_engine("decorated-mine", r=0.9), Mine)
    finally:
        ENGINES.pop("lazy-mine", None)
        ENGINES.pop("decorated-mine", None)


def test_a_subclass_registered_under_its_own_name_keeps_its_parents_facts():
    pybullet = engine_class("pybullet")
    try:
        sub = register_engine("pybullet-mine")(type("PybulletMine", (pybullet,), {}))
        assert ENGINES["pybullet-mine"].distribution == "pybullet" and sub.LABEL == "PyBullet"
        assert sub.package == "pybullet"
    finally:
        ENGINES.pop("pybullet-mine", None)


def test_a_class_or_entry_point_stored_directly_becomes_a_spec(monkeypatch):
    """``ENGINES[name] = cls`` (the registry's values before the specs) still registers an engine."""
    monkeypatch.setitem(ENGINES, "stored-mine", HousnerEngine)
    assert ENGINES["stored-mine"] == EngineSpec.from_class("stored-mine", HousnerEngine)
    assert engine_class("stored-mine") is HousnerEngine and ENGINES["stored-mine"].distribution == "housner"
    ENGINES.setdefault("stored-lazy", "housner.engines.analytic:HousnerEngine")
    try:
        assert engine_class("stored-lazy") is HousnerEngine and ENGINES["stored-lazy"].distribution == ""
    finally:
        del ENGINES["stored-lazy"]
    with pytest.raises(ValueError, match="cannot be registered as"):
        ENGINES["other"] = ENGINES["housner"]


@pytest.mark.parametrize(
    ("entry", "error"),
    [("no_colon", ValueError), (":Cls", ValueError), (42, TypeError)],
    ids=["no-colon", "no-module", "int"],
)
def test_a_bad_entry_point_is_refused(entry, error):
    with pytest.raises(error, match="entry point"):
        EngineSpec("bad", entry)


def test_an_unknown_name_lists_the_choices():
    with pytest.raises(ValueError, match=r"unknown engine 'mujocco'; did you mean 'mujoco'\?"):
        get_engine("mujocco")
