"""The analytic kernel of a set of terms (:mod:`housner.effects.terms`): generated code, cached on disk.

For each *structure* (which functions, of which kind) this module writes the plain kernel's
:mod:`housner._kernel_steps`, its hook section replaced by calls to the terms' functions, and
:mod:`housner._kernel` importing it, into the kernel directory (:func:`kernel_dir`), named by a SHA-256 of
what they are made of, and imports them; numba caches their machine code next to them. The cache heals
itself: a generated file or numba cache file that does not load is removed and made again, each repair
counted (:func:`kernel_cache_repairs`) and logged. A term's function must be importable by its module and
qualified name, and only its own module's source enters the file name. How the files are named, written,
checked and repaired is in ``docs/reference/effects-api.md`` ("How the kernel of a set of terms is made");
why generated code, in ``docs/results.md#defaults-terms``.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import logging
import marshal
import os
import pickle
import sys
import tempfile
import threading
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["compiled_kernel", "generated_source", "import_file", "kernel_cache_repairs", "kernel_dir", "kernel_module"]

_LOG = logging.getLogger(__name__)

#: The plain kernel's modules: the steps (with the hooks), the record loop (importing the steps), the parts.
_CORE = Path(__file__).resolve().parent.parent
_STEPS, _RUN, _PARTS = _CORE / "_kernel_steps.py", _CORE / "_kernel.py", _CORE / "_kernel_parts.py"
_BEGIN, _END = "# <hooks>\n", "# </hooks>\n"
_STEPS_IMPORT = "from housner._kernel_steps import (\n"


# ----------------------------------------------------------------------
# the generated kernels
def kernel_dir() -> Path:
    """Where generated kernels (and numba's cache of them) are written.

    ``HOUSNER_KERNEL_DIR``, else ``$HOUSNER_CACHE_DIR/kernels``, else ``~/.cache/housner/kernels``;
    a private temporary folder when that cannot be written (then nothing is kept across processes).
    """
    global _FALLBACK
    env = os.environ.get("HOUSNER_KERNEL_DIR")
    if env:
        d = Path(env).expanduser()
    else:
        base = os.environ.get("HOUSNER_CACHE_DIR")
        d = (Path(base).expanduser() if base else Path.home() / ".cache" / "housner") / "kernels"
    try:
        d.mkdir(parents=True, exist_ok=True)
        if os.access(d, os.W_OK):
            return d
    except OSError:
        pass
    if _FALLBACK is None:
        _FALLBACK = Path(tempfile.mkdtemp(prefix="housner-kernels-"))
    return _FALLBACK


_FALLBACK: Path | None = None
_MODULES: dict[tuple, ModuleType] = {}
_LOCK = threading.Lock()


def _source_bytes(module: str, names: tuple[str, ...] = ()) -> bytes:
    """The source file of ``module``; for a module without one (an interactive session), the compiled code of its
    term functions ``names`` (qualified names), so that a function typed again differently gets a new kernel."""
    try:
        mod = sys.modules.get(module) or importlib.import_module(module)
    except ImportError:
        return b""
    try:
        path = inspect.getsourcefile(mod)
        if path:
            return Path(path).read_bytes()
    except (TypeError, OSError):
        pass
    out = b""
    for qual in names:
        obj = mod
        for part in qual.split("."):
            obj = getattr(obj, part, None)
        code = getattr(getattr(obj, "py_func", obj), "__code__", None)  # a numba dispatcher keeps its Python function
        if code is not None:
            out += qual.encode() + b"\0" + marshal.dumps(code)
    return out


def _hooks(structure: tuple) -> str:
    """The hook section of the kernel template for ``structure`` (see
    :attr:`housner.effects.terms.TermSet.structure`).

    Its text is part of every generated kernel's name (:func:`kernel_module`). The generated code imports
    the term functions through ``housner.effects.terms._import_term``, which lives with the term types
    (``TermSet`` uses it too).
    """
    lo = 0
    calls: dict[str, list[str]] = {"moment": [], "coulomb": [], "impact": []}
    imports = []
    for i, (kind, mod, qual, nq, _flag) in enumerate(structure):
        imports.append(f"_term{i} = _import_term({mod!r}, {qual!r})")
        sl = f"q[{lo}:{lo + nq}]"
        lo += nq
        if kind == "moment":
            calls[kind].append(f"_term{i}(phi, w, t, a, v, s, alpha, p2, {sl})")
        elif kind == "coulomb":
            calls[kind].append(f"_term{i}(phi, t, a, v, s, alpha, p2, {sl})")
        else:
            calls[kind].append(f"    r = _term{i}(w, r, s, alpha, p2, {sl})")
    at_rest = any(k == "coulomb" or (k == "moment" and flag) for k, _m, _q, _n, flag in structure)
    return "\n".join(
        [
            _BEGIN.rstrip("\n"),
            f"HAS_MOMENT = {bool(calls['moment'])}",
            f"HAS_DRY = {bool(calls['coulomb'])}",
            f"HAS_IMPACT = {bool(calls['impact'])}",
            f"AT_REST = {at_rest}",
            "",
            "from housner.effects.terms import _import_term  # noqa: E402",
            "",
            *imports,
            "",
            "",
            "@njit(cache=True)",
            "def _moment(phi, w, t, a, v, s, alpha, p2, q):",
            "    return " + (" + ".join(calls["moment"]) or "0.0"),
            "",
            "",
            "@njit(cache=True)",
            "def _dry(phi, t, a, v, s, alpha, p2, q):",
            "    return " + (" + ".join(calls["coulomb"]) or "0.0"),
            "",
            "",
            "@njit(cache=True)",
            "def impact_ratio(w, r, s, alpha, p2, q):",
            *calls["impact"],
            "    return r",
            "",
            "",
            _END,
        ]
    )


def generated_source(structure: tuple, steps_module: str = "housner._kernel_steps") -> tuple[str, str]:
    """The texts of the kernel's two modules for ``structure``: :mod:`housner._kernel_steps` with its
    hooks replaced, and :mod:`housner._kernel` importing it as ``steps_module``."""
    head = (
        "# Generated by housner.effects.codegen from housner/{}; do not edit.\n"
        f"# Terms: {', '.join(f'{k} {m}.{q}' for k, m, q, _n, _f in structure) or 'none'}\n"
    )
    text = _STEPS.read_text()
    i, j = text.index(_BEGIN), text.index(_END) + len(_END)
    steps = head.format(_STEPS.name) + text[:i] + _hooks(structure) + text[j:]
    run = _RUN.read_text()
    if run.count(_STEPS_IMPORT) != 1:
        raise RuntimeError(f"{_RUN} must import the steps once as {_STEPS_IMPORT.strip()!r}")
    return steps, head.format(_RUN.name) + run.replace(_STEPS_IMPORT, f"from {steps_module} import (\n")


def import_file(name: str, path: Path) -> ModuleType:
    """Import the Python file ``path`` as module ``name``, kept in ``sys.modules`` (so that numba finds
    its functions by module and qualified name); a file that raises leaves nothing behind."""
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    try:
        spec.loader.exec_module(mod)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return mod


def kernel_module(structure: tuple) -> ModuleType:
    """The compiled kernel for ``structure`` (its record loop's module): written to :func:`kernel_dir` once,
    imported once per process; a damaged file or numba cache file of it is removed and rebuilt first."""
    with _LOCK:
        mod = _MODULES.get(structure)
        if mod is not None:
            return mod
        h = hashlib.sha256(_hooks(structure).encode())
        for f in (_STEPS, _RUN, _PARTS):
            h.update(f.read_bytes())
        for m in sorted({s[1] for s in structure}):
            h.update(m.encode() + b"\0" + _source_bytes(m, tuple(sorted({s[2] for s in structure if s[1] == m}))))
        name = f"housner_terms_{h.hexdigest()[:24]}"
        d = kernel_dir()
        steps, run = generated_source(structure, f"{name}_steps")
        rebuilt = [stem for stem, src in ((f"{name}_steps", steps), (name, run)) if _ensure_file(d / f"{stem}.py", src)]
        steps_mod = import_file(f"{name}_steps", d / f"{name}_steps.py")  # first: the loop's module imports it by name
        mod = import_file(name, d / f"{name}.py")
        for m in (steps_mod, mod):
            _check_numba_cache(m, drop=m.__name__ in rebuilt)
        _MODULES[structure] = mod
        return mod


# ----------------------------------------------------------------------
# the cache's repairs
_REPAIRS = {"kernel_files": 0, "numba_caches": 0, "numba_retries": 0}


def kernel_cache_repairs() -> dict[str, int]:
    """The damaged kernel-cache entries this process found, removed and rebuilt.

    Returns
    -------
    dict
        ``kernel_files``: generated kernel files whose content did not match their key (truncated,
        garbled); ``numba_caches``: functions whose numba cache files (index or data) did not load;
        ``numba_retries``: kernel calls run again without the cache files after numba failed to load
        them. All zero in a healthy cache.
    """
    return dict(_REPAIRS)


def _ensure_file(path: Path, src: str) -> bool:
    """Write ``src`` to ``path`` unless it already holds exactly that; True when a damaged file was replaced.

    The name hashes everything the text is made from, so the text itself is the file's content key.
    A file that holds it is left alone (rewriting would change its stamp and void numba's cache); one
    that does not is damaged and written again, atomically, as is a missing one.
    """
    want = src.encode()
    try:
        have = path.read_bytes()
    except FileNotFoundError:
        have = None
    if have == want:
        return False
    # write once, atomically (a temporary file in the same folder, then os.replace): a process killed
    # mid-write leaves a stray temporary file, never a half-written kernel
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(want)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    if have is None:
        return False
    _REPAIRS["kernel_files"] += 1
    _LOG.warning("kernel cache: %s did not match its key (%d bytes, %d expected); rebuilt", path, len(have), len(want))
    return True


def _cache_dir(mod: ModuleType) -> Path | None:
    """Where numba keeps the cache of ``mod``'s functions (None when it holds no cached function)."""
    for obj in vars(mod).values():
        cache = getattr(obj, "_cache", None)
        py = getattr(obj, "py_func", None)
        if py is not None and py.__module__ == mod.__name__ and getattr(cache, "cache_path", None):
            return Path(cache.cache_path)
    return None


def _numba_files(mod: ModuleType) -> list[Path]:
    """numba's cache files (``<file stem>.<function>-<line>.pyXY[.n].nbi/.nbc``) of ``mod``'s functions."""
    d = _cache_dir(mod)
    if d is None or not d.is_dir():
        return []
    stem = Path(mod.__file__).stem
    return [p for p in d.glob(f"{stem}.*") if p.suffix in (".nbi", ".nbc")]


def _unloadable(index: Path) -> tuple[Path, Exception] | None:
    """The file of numba's cache index ``index`` (it, or a data file it lists) that would not load as numba
    reads it, with the error; None when all load."""
    import numba

    path = index
    try:
        with open(index, "rb") as f:
            version = pickle.load(f)
            rest = f.read()
        if version != numba.__version__:
            return None  # numba skips an index of another version without reading the rest
        _stamp, overloads = pickle.loads(rest)
        for data_name in dict(overloads).values():
            path = index.parent / data_name
            if path.exists():
                pickle.loads(path.read_bytes())
    except FileNotFoundError:
        return None  # removed meanwhile by another process
    except Exception as e:  # anything pickle raises on garbage: UnpicklingError, EOFError, MemoryError, ...
        return path, e
    return None


def _check_numba_cache(mod: ModuleType, drop: bool = False) -> None:
    """Remove the numba cache files of ``mod``'s functions that would not load (all of them if ``drop``)."""
    files = _numba_files(mod)
    if drop:
        for p in files:
            p.unlink(missing_ok=True)
        return
    for index in (p for p in files if p.suffix == ".nbi"):
        bad = _unloadable(index)
        if bad is None:
            continue
        base = index.name[: -len(".nbi")]
        for p in [index, *index.parent.glob(f"{base}.*.nbc")]:
            p.unlink(missing_ok=True)
        _REPAIRS["numba_caches"] += 1
        _LOG.warning(
            "kernel cache: numba's %s does not load (%s: %s); its cache removed, recompiling",
            bad[0],
            type(bad[1]).__name__,
            bad[1],
        )


def _raised_by_numba_cache(e: BaseException) -> bool:
    """Whether ``e`` was raised while numba loaded a cached function (its traceback passes numba's caching)."""
    tb = e.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_filename.replace(os.sep, "/").endswith("numba/core/caching.py"):
            return True
        tb = tb.tb_next
    return False


def compiled_kernel(structure: tuple) -> Any:
    """The compiled kernel of ``structure`` (:func:`kernel_module`), whose entry points (``run_one``,
    ``run_batch``, ``run_batch_parallel``) run again once without numba's cache files when loading those
    raises."""
    return _HealingKernel(kernel_module(structure))


class _HealingKernel:
    """A generated kernel module whose entry points run again once without numba's cache files when
    numba fails to load those (damaged after :func:`kernel_module` checked them); every other name is
    the module's."""

    _ENTRIES = ("run_one", "run_batch", "run_batch_parallel")

    def __init__(self, mod: ModuleType):
        self._mod = mod

    def __getattr__(self, name: str) -> Any:
        fn = getattr(self._mod, name)
        if name not in self._ENTRIES:
            return fn
        mod = self._mod

        def call(*args, **kwargs):
            try:
                return fn(*args, **kwargs)
            except Exception as e:
                if not _raised_by_numba_cache(e):
                    raise
                _REPAIRS["numba_retries"] += 1
                _LOG.warning(
                    "kernel cache: numba failed to load %s.%s (%s: %s); its cache removed, recompiling",
                    mod.__name__,
                    name,
                    type(e).__name__,
                    e,
                )
                for m in {mod, sys.modules.get(f"{mod.__name__}_steps")} - {None}:
                    _check_numba_cache(m, drop=True)
                return fn(*args, **kwargs)

        call.__name__ = call.__qualname__ = name
        return call
