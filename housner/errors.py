"""Named errors of the suite."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from pathlib import Path

__all__ = ["DataFileError", "EngineError", "EngineUnavailable", "one_line", "unknown_choice"]


class DataFileError(ValueError):
    """A data file is malformed; the message names the file, line and column.

    Attributes
    ----------
    path : pathlib.Path
    line : int or None
        1-based line number in the file.
    column : str or None
        Column name (CSV files).
    """

    def __init__(self, path: str | Path, message: str, *, line: int | None = None, column: str | None = None):
        self.path = Path(path)
        self.line = line
        self.column = column
        where = str(self.path)
        if line is not None:
            where += f" line {line}"
        if column is not None:
            where += f", column `{column}`"
        super().__init__(f"{where}: {message}")


class EngineError(RuntimeError):
    """An engine failed or diverged on a record (the message says which and why)."""


class EngineUnavailable(EngineError):
    """An engine's package (or a system library it needs) is not installed; the message names the install command."""


def unknown_choice(kind: str, name: str, choices: Iterable[str]) -> ValueError:
    """A ``ValueError`` for an unknown registry key that lists the choices and suggests the closest."""
    choices = sorted(choices)
    msg = f"unknown {kind} {name!r}"
    close = difflib.get_close_matches(str(name), choices, n=1)
    if close:
        msg += f"; did you mean {close[0]!r}?"
    msg += f" (choices: {', '.join(choices)})"
    return ValueError(msg)


def one_line(message: object) -> str:
    """A message, or an exception's, on one line: its non-empty lines joined by "; ".

    An exception without text gives its type's name, so that an error line never ends empty.
    """
    text = "; ".join(line.strip() for line in str(message).splitlines() if line.strip())
    return text or (type(message).__name__ if isinstance(message, BaseException) else "")
