"""mkdocs hook: let mkdocstrings find ``housner.engines``, ``housner.scenarios`` and ``housner.reports``.

The wheel installs the repository's folders ``engines/``, ``scenarios/`` and ``reports/`` as sub-packages of
``housner`` (``[tool.setuptools.package-dir]`` in ``pyproject.toml``). griffe, which reads the sources for
mkdocstrings, looks for ``housner.engines`` in ``housner/engines/`` and finds nothing. Before the build this
hook lays out the installed shape in a temporary folder, ``housner/`` with a symbolic link to every entry of
the repository's ``housner/`` and to each mapped folder, and puts it first on mkdocstrings' search paths.
Nothing in the repository is written.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from pathlib import Path

from mkdocs.plugins import event_priority

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


#: The repository: this file is docs/hooks/api_sources.py.
ROOT = Path(__file__).resolve().parents[2]


def _package_dirs(root: Path) -> dict[str, Path]:
    """Import name -> folder, from pyproject's ``[tool.setuptools.package-dir]``."""
    conf = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))
    return {name: root / folder for name, folder in conf["tool"]["setuptools"]["package-dir"].items()}


def _link(target: Path, link: Path) -> None:
    if link.is_symlink() or link.exists():
        if link.is_symlink() and Path(os.readlink(link)) == target:
            return
        link.unlink()
    link.symlink_to(target, target_is_directory=target.is_dir())


def installed_layout(root: Path) -> Path:
    """A folder holding ``housner/`` as the wheel installs it (links into ``root``); returns the folder."""
    dirs = _package_dirs(root)
    top = dirs.pop("housner")
    digest = hashlib.sha256(str(root.resolve()).encode()).hexdigest()[:12]
    base = Path(tempfile.gettempdir()) / f"housner-docs-{digest}"
    pkg = base / "housner"
    pkg.mkdir(parents=True, exist_ok=True)
    wanted = {}
    for entry in top.iterdir():
        if entry.name != "__pycache__":
            wanted[entry.name] = entry
    for name, folder in dirs.items():
        parent, _, child = name.rpartition(".")
        if parent != "housner":
            raise ValueError(f"package-dir maps {name!r}: only direct sub-packages of housner are laid out")
        wanted[child] = folder
    for link in pkg.iterdir():
        if link.name not in wanted:
            link.unlink()
    for name, target in wanted.items():
        _link(target.resolve(), pkg / name)
    return base


@event_priority(100)  # before mkdocstrings reads its handler's configuration
def on_config(config):
    root = ROOT
    base = installed_layout(root)
    handler = config.plugins["mkdocstrings"].config.handlers.setdefault("python", {})
    paths = list(handler.get("paths", []))
    handler["paths"] = [str(base), *(p for p in paths if p != str(base))]
    return config
