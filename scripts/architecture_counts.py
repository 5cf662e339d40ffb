"""Architecture counts of issue 39, by AST over the package's source, outside tests: underscore names imported
across modules, names re-exported by modules that are not a package's ``__init__``, modules over 600 lines,
functions over 80 lines, and the legacy import hook. What each counts, exactly, is in ``docs/development.md``
("Architecture counts").

Usage::

    python scripts/architecture_counts.py
    python scripts/architecture_counts.py --json counts.json
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 80


def source_roots(root: Path) -> dict[str, Path]:
    """Import name -> source folder, from ``[tool.setuptools.package-dir]``."""
    with open(root / "pyproject.toml", "rb") as fh:
        cfg = tomllib.load(fh)
    dirs = cfg["tool"]["setuptools"]["package-dir"]
    return {name: root / folder for name, folder in dirs.items()}


def is_test_path(rel: Path) -> bool:
    """True for files the counts leave out: tests folders and test files."""
    return "tests" in rel.parts or rel.name.startswith("test_") or rel.name == "conftest.py"


def discover(root: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every counted module."""
    modules: dict[str, Path] = {}
    roots = source_roots(root)
    for pkg, folder in roots.items():
        for path in sorted(folder.rglob("*.py")):
            rel = path.relative_to(folder)
            if is_test_path(rel) or "__pycache__" in rel.parts:
                continue
            # a folder mapped to its own import name is not also a subpackage
            first = rel.parts[0]
            if len(rel.parts) > 1 and f"{pkg}.{first}" in roots:
                continue
            parts = list(rel.with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            name = ".".join([pkg, *parts])
            modules[name] = path
    return modules


def is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def resolve(module: str, is_pkg: bool, node: ast.ImportFrom) -> str:
    """The absolute module an ``ImportFrom`` names."""
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_pkg:
        base = base[:-1]
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def underscore_imports(module: str, is_pkg: bool, tree: ast.Module) -> list[dict]:
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom):
            continue
        source = resolve(module, is_pkg, node)
        if source != "housner" and not source.startswith("housner."):
            continue
        if source == module:
            continue
        if is_pkg and (source == module or source.rsplit(".", 1)[0] == module):
            continue  # a package's __init__ and its own modules
        for alias in node.names:
            if is_private(alias.name):
                found.append({"name": alias.name, "from": source, "line": node.lineno})
    return found


def _top_level_statements(body: list[ast.stmt]):
    """Module-level statements, descending into if/try/with blocks (not defs)."""
    for stmt in body:
        yield stmt
        if isinstance(stmt, ast.If):
            yield from _top_level_statements(stmt.body)
            yield from _top_level_statements(stmt.orelse)
        elif isinstance(stmt, ast.Try):
            yield from _top_level_statements(stmt.body)
            for h in stmt.handlers:
                yield from _top_level_statements(h.body)
            yield from _top_level_statements(stmt.orelse)
            yield from _top_level_statements(stmt.finalbody)
        elif isinstance(stmt, (ast.With, ast.For, ast.While)):
            yield from _top_level_statements(stmt.body)


def _target_names(target: ast.expr) -> set[str]:
    return {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}


def _dunder_all(tree: ast.Module) -> list[str]:
    names: list[str] = []
    for stmt in _top_level_statements(tree.body):
        targets: list[ast.expr] = []
        value = None
        if isinstance(stmt, ast.Assign):
            targets, value = stmt.targets, stmt.value
        elif isinstance(stmt, (ast.AugAssign, ast.AnnAssign)):
            targets, value = [stmt.target], stmt.value
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            if isinstance(value, (ast.List, ast.Tuple)):
                names += [e.value for e in value.elts if isinstance(e, ast.Constant)]
    return names


def _string_annotation_names(tree: ast.Module) -> set[str]:
    names: set[str] = set()
    annotations: list[ast.expr] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            for a in [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]:
                if a is not None and a.annotation is not None:
                    annotations.append(a.annotation)
            if node.returns is not None:
                annotations.append(node.returns)
        elif isinstance(node, ast.AnnAssign):
            annotations.append(node.annotation)
    for ann in annotations:
        for sub in ast.walk(ann):
            if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                try:
                    parsed = ast.parse(sub.value, mode="eval")
                except SyntaxError:
                    continue
                names |= {n.id for n in ast.walk(parsed) if isinstance(n, ast.Name)}
    return names


def reexports(module: str, tree: ast.Module) -> list[dict]:
    defined: set[str] = set()
    imported: dict[str, dict] = {}
    for stmt in _top_level_statements(tree.body):
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            defined.add(stmt.name)
        elif isinstance(stmt, ast.Assign):
            for t in stmt.targets:
                defined |= _target_names(t)
        elif isinstance(stmt, (ast.AnnAssign, ast.AugAssign)):
            defined |= _target_names(stmt.target)
        elif isinstance(stmt, (ast.For, ast.AsyncFor)):
            defined |= _target_names(stmt.target)
        elif isinstance(stmt, ast.With):
            for item in stmt.items:
                if item.optional_vars is not None:
                    defined |= _target_names(item.optional_vars)
        elif isinstance(stmt, ast.Import):
            for alias in stmt.names:
                bound = alias.asname or alias.name.split(".")[0]
                imported[bound] = {"from": alias.name, "line": stmt.lineno}
        elif isinstance(stmt, ast.ImportFrom):
            if stmt.module == "__future__":
                continue
            source = resolve(module, False, stmt)
            for alias in stmt.names:
                if alias.name == "*":
                    continue
                imported[alias.asname or alias.name] = {"from": source, "line": stmt.lineno}
    used: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Store):
            used.add(node.id)
    used |= _string_annotation_names(tree)
    exported = set(_dunder_all(tree))
    found = []
    for name in sorted(set(imported) | exported):
        if name in defined:
            continue
        in_all = name in exported
        unused = name in imported and name not in used
        if not (in_all or unused):
            continue
        if name not in imported:
            # in __all__ but neither defined nor imported here: a dangling entry
            found.append({"name": name, "from": None, "line": None, "why": "__all__, not bound"})
            continue
        why = " and ".join(w for w, ok in (("__all__", in_all), ("imported, unused", unused)) if ok)
        found.append({"name": name, **imported[name], "why": why})
    return found


def long_functions(tree: ast.Module) -> list[dict]:
    found = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                qual = f"{prefix}{child.name}"
                length = child.end_lineno - child.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    found.append({"name": qual, "line": child.lineno, "lines": length})
                visit(child, f"{qual}.<locals>.")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(tree, "")
    return found


def count(root: Path = ROOT) -> dict:
    modules = discover(root)
    details: dict = {
        "underscore_imports": {},
        "reexports": {},
        "long_modules": {},
        "long_functions": {},
    }
    for name, path in modules.items():
        rel = str(path.relative_to(root))
        text = path.read_text(encoding="utf-8")
        tree = ast.parse(text, filename=rel)
        is_pkg = path.name == "__init__.py"
        if u := underscore_imports(name, is_pkg, tree):
            details["underscore_imports"][rel] = u
        if not is_pkg and (r := reexports(name, tree)):
            details["reexports"][rel] = r
        n_lines = len(text.splitlines())
        if n_lines > MAX_MODULE_LINES:
            details["long_modules"][rel] = n_lines
        if f := long_functions(tree):
            details["long_functions"][rel] = f
    details["legacy"] = (root / "housner" / "_legacy.py").exists()
    details["modules"] = len(modules)
    details["summary"] = {
        "modules counted": len(modules),
        "underscore names imported across modules": sum(len(v) for v in details["underscore_imports"].values()),
        "  in importing files": len(details["underscore_imports"]),
        "names re-exported by non-__init__ modules": sum(len(v) for v in details["reexports"].values()),
        "  by modules": len(details["reexports"]),
        f"modules over {MAX_MODULE_LINES} lines": len(details["long_modules"]),
        f"functions over {MAX_FUNCTION_LINES} lines": sum(len(v) for v in details["long_functions"].values()),
        "housner/_legacy.py exists": details["legacy"],
    }
    return details


def print_report(details: dict, verbose: bool) -> None:
    summary = details["summary"]
    width = max(len(k) for k in summary)
    print(f"{'count':<{width}}  value")
    print(f"{'-' * width}  -----")
    for key, value in summary.items():
        print(f"{key:<{width}}  {'yes' if value is True else 'no' if value is False else value}")
    if not verbose:
        return
    print("\nunderscore names imported across modules:")
    for rel, items in details["underscore_imports"].items():
        names = ", ".join(f"{i['name']} ({i['from']})" for i in items)
        print(f"  {rel} [{len(items)}]: {names}")
    print("\nre-exports by non-__init__ modules:")
    for rel, items in details["reexports"].items():
        names = ", ".join(f"{i['name']} [{i['why']}]" for i in items)
        print(f"  {rel} [{len(items)}]: {names}")
    print(f"\nmodules over {MAX_MODULE_LINES} lines:")
    for rel, n in sorted(details["long_modules"].items(), key=lambda kv: -kv[1]):
        print(f"  {n:5d}  {rel}")
    print(f"\nfunctions over {MAX_FUNCTION_LINES} lines:")
    rows = [(f["lines"], rel, f) for rel, fs in details["long_functions"].items() for f in fs]
    for n, rel, f in sorted(rows, key=lambda r: -r[0]):
        print(f"  {n:5d}  {rel}:{f['line']}  {f['name']}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", metavar="F", help="write the details to this file")
    ap.add_argument("-v", "--verbose", action="store_true", help="list every item under the table")
    ap.add_argument("--root", type=Path, default=ROOT, help="repository root (this checkout)")
    args = ap.parse_args(argv)
    details = count(args.root)
    print_report(details, args.verbose)
    if args.json:
        Path(args.json).write_text(json.dumps(details, indent=2) + "\n", encoding="utf-8")
        print(f"\ndetails: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
