"""Check output paths before any work is done.

A run or a diagnosis can take minutes; an output path that cannot be written
must be refused before it starts, with one line that names the path and the
option it came from. Both checks create what they need (the directory, its
parents) and write then delete a probe file, so "writable" is tested, not
guessed from permission bits.

A run or study directory's files are replaced only when they are a previous
run's: a user's own ``results.parquet`` or ``report.html`` in ``--out`` is not
overwritten without a word. A previous run is known by its manifest
(``run.json`` or ``study.json``, a JSON object with the scenario and housner's
provenance, as :func:`housner.scenarios.execution.rundir.provenance` writes it).
"""

from __future__ import annotations

import errno
import json
import os
import uuid
from collections.abc import Iterable
from pathlib import Path

__all__ = ["OutputPathError", "check_output_dir", "check_output_file"]


class OutputPathError(ValueError):
    """An output path cannot be used; the message names the option and the path.

    Attributes
    ----------
    path : pathlib.Path
    what : str
        Where the path came from (an option such as ``--out``, or a description).
    """

    def __init__(self, what: str, path: str | Path, message: str):
        self.path = Path(path)
        self.what = what
        super().__init__(f"{what} {self.path}: {message}")


def _reason(e: OSError) -> str:
    if e.errno == errno.ENOTDIR:
        return "a part of the path is a file, not a directory"
    if e.errno == errno.EEXIST:
        return "exists and is not a directory"
    if e.errno in (errno.EACCES, errno.EPERM):
        return "permission denied"
    if e.errno == errno.EROFS:
        return "read-only file system"
    if e.errno == errno.ENOSPC:
        return "no space left on the device"
    if e.errno == errno.ENOENT:
        return "no such file or directory"
    return e.strerror or type(e).__name__


#: The manifests of a run and a study directory: a caller that writes one writes a run (or study) directory.
MANIFESTS = ("run.json", "study.json")
#: A manifest larger than this is not read to recognise it [bytes] (a run.json is a few hundred kB at most).
_MANIFEST_MAX = 64 * 2**20


def _is_housner_manifest(path: Path) -> bool:
    """True if ``path`` is a run.json / study.json housner wrote: a JSON object with the scenario and
    housner's version in its provenance."""
    try:
        if not path.is_file() or path.stat().st_size > _MANIFEST_MAX:
            return False
        data = json.loads(path.read_bytes())
    except (OSError, ValueError):
        return False
    prov = data.get("provenance") if isinstance(data, dict) else None
    versions = prov.get("versions") if isinstance(prov, dict) else None
    return "scenario" in data and isinstance(versions, dict) and "housner" in versions


def _refuse_foreign(path: Path, what: str, files: list[str]) -> None:
    """Refuse to write a run or study directory over files of its names that no housner run wrote there."""
    if not any(name in MANIFESTS for name in files):
        return
    present = [name for name in files if (path / name).is_file()]
    if not present or any(_is_housner_manifest(path / m) for m in MANIFESTS):
        return
    raise OutputPathError(
        what,
        path,
        f"{present[0]!r} inside it is not from a housner run (no run.json or study.json of one beside it) and "
        f"would be overwritten; give another {what} or remove the file",
    )


def _probe(directory: Path, what: str, shown: Path) -> None:
    """Create and delete a probe file in ``directory`` (raises OutputPathError)."""
    probe = directory / f".housner-write-probe-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        with open(probe, "wb") as f:
            f.write(b"probe")
    except OSError as e:
        raise OutputPathError(what, shown, f"not writable ({_reason(e)})") from None
    finally:
        try:
            probe.unlink()
        except OSError:
            pass


def _make_dir(path: Path, what: str, shown: Path) -> None:
    try:
        if path.exists() and not path.is_dir():
            raise OutputPathError(what, shown, "exists and is a file, not a directory")
        path.mkdir(parents=True, exist_ok=True)
    except FileExistsError:  # a file (or a dangling link) took the name
        raise OutputPathError(what, shown, "exists and is not a directory") from None
    except OSError as e:
        raise OutputPathError(what, shown, f"cannot create the directory ({_reason(e)})") from None


def check_output_dir(path: str | Path, what: str = "output directory", files: Iterable[str] = ()) -> Path:
    """Make sure ``path`` is a writable directory (created if need be).

    Parameters
    ----------
    path : str or pathlib.Path
        The directory.
    what : str
        The option or role named in the error (``--out``).
    files : iterable of str
        Names of files the caller will write in the directory: none may be a directory. When they
        include a manifest (:data:`MANIFESTS`: a run or a study directory), those that exist must be a
        previous housner run's: a directory without a housner run.json / study.json whose files of
        these names exist is refused, so that a user's own files are not overwritten.

    Returns
    -------
    pathlib.Path
        ``path``, which now exists and accepts new files.

    Raises
    ------
    OutputPathError
        The path is a file, lies under a file, cannot be created or is not writable, or holds a
        file of a run's name that no housner run wrote.
    """
    path = Path(path)
    files = list(files)
    _make_dir(path, what, path)
    _probe(path, what, path)
    _refuse_foreign(path, what, files)
    for name in files:
        target = path / name
        if target.is_dir():
            raise OutputPathError(what, path, f"{name!r} inside it is a directory; the run writes a file there")
        if target.exists() and not os.access(target, os.W_OK):
            raise OutputPathError(what, path, f"{name!r} inside it is not writable")
    return path


def check_output_file(path: str | Path, what: str = "output file") -> Path:
    """Make sure a file can be written at ``path`` (its directory is created if need be).

    Parameters
    ----------
    path : str or pathlib.Path
        The file to be written (it may exist: it will be replaced).
    what : str
        The option or role named in the error (``--json``, ``--report``).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    OutputPathError
        The path is a directory, its directory cannot be created or is not
        writable, or the file exists and is not writable.
    """
    raw = os.fspath(path)
    path = Path(path)
    if path.is_dir():
        raise OutputPathError(what, path, "is a directory; give a file name")
    if raw.endswith(("/", os.sep)):
        raise OutputPathError(what, path, "ends with a slash, so it names a directory; give a file name")
    parent = path.parent if str(path.parent) else Path(".")
    for above in (parent, *parent.parents):
        try:
            if above.exists():
                if not above.is_dir():
                    raise OutputPathError(what, path, f"{above} is a file, not a directory")
                break
        except OSError:
            break
    _make_dir(parent, what, path)
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputPathError(what, path, "exists and is not writable")
    _probe(parent, what, path)
    return path
