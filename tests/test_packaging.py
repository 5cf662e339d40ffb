"""One import name: every package is in the wheel's list, and ``housner`` is the only import name."""

import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = {
    "housner": "housner",
    "engines": "housner.engines",
    "scenarios": "housner.scenarios",
    "reports": "housner.reports",
}


def test_every_package_and_data_folder_is_listed_for_the_wheel():
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(conf["packages"])
    assert {k: v for k, v in conf["package-dir"].items()} == {v: k for k, v in FOLDERS.items()}
    found = set()
    for folder, name in FOLDERS.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder).parts
            found.add(".".join((name, *rel)))
    assert found <= listed, f"packages missing from pyproject's list: {sorted(found - listed)}"
    for data in ("engines/models", "scenarios/catalogue/data"):  # folders of data files, listed as packages
        folder, *rest = data.split("/")
        assert ".".join((FOLDERS[folder], *rest)) in listed


def _run(code: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-W", "always", "-c", code], cwd=cwd, capture_output=True, text=True, timeout=120
    )


def test_housner_installs_no_other_import_name(tmp_path):
    """``housner`` answers for no other top-level name: outside a checkout, ``scenarios`` is simply not found."""
    r = _run("import housner\ntry:\n    import scenarios\nexcept ModuleNotFoundError:\n    print('absent')\n", tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "absent"
    assert not any("housner" in type(f).__module__ for f in sys.meta_path)


def test_a_users_own_package_of_a_folders_name_wins(tmp_path):
    (tmp_path / "scenarios").mkdir()
    (tmp_path / "scenarios" / "__init__.py").write_text("MINE = 1\n")
    r = _run("import housner, scenarios\nassert scenarios.MINE == 1\n", tmp_path)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("name", ["engines", "scenarios", "reports"])
def test_a_checkout_folder_imported_by_its_own_name_refuses_in_one_line(name):
    """From the repository's root, ``import scenarios`` finds the folder itself: it refuses, naming the import."""
    r = _run(f"import {name}\n", ROOT)
    assert r.returncode == 1
    assert f"ImportError: `{name}` is not an import name of this project: import `housner.{name}`" in r.stderr


@pytest.mark.parametrize("package", ["housner.scenarios", "housner.scenarios.execution"])
def test_lazy_exports_are_the_public_names(package):
    """The packages export on first use (PEP 562): every name of ``__all__`` has a module, and resolves."""
    import importlib

    mod = importlib.import_module(package)
    assert set(mod.__all__) == set(mod._EXPORTS)
    for name in mod.__all__:
        assert getattr(mod, name) is not None and name in dir(mod)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        mod.nothing  # noqa: B018


def test_a_worker_imports_its_chunks_without_the_diagnosis():
    """What a pool worker loads to run records: no campaign, diagnosis, runner or report module (it was 1.45 s of
    imports with them, 0.16 s without, measured)."""
    code = (
        "import sys, housner.scenarios.execution.chunks; "
        "print(sorted(m for m in sys.modules if m.startswith(('housner.scenarios.campaigns', "
        "'housner.scenarios.diagnosis', 'housner.scenarios.execution.runner', 'housner.reports', 'matplotlib'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
