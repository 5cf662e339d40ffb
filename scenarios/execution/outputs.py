"""Check output paths before any work is done.

A run or a diagnosis can take minutes; an output path that cannot be written
must be refused before it starts, with one line that names the path and the
option it came from. Both checks create what they need (the directory, its
parents) and write then delete a probe file, so "writable" is tested, not
guessed from permission bits.
"""

from __future__ import annotations

import errno
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
        Names of files the caller will write in the directory: none may be a directory.

    Returns
    -------
    pathlib.Path
        ``path``, which now exists and accepts new files.

    Raises
    ------
    OutputPathError
        The path is a file, lies under a file, cannot be created or is not writable.
    """
    path = Path(path)
    _make_dir(path, what, path)
    _probe(path, what, path)
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
