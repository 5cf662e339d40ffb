"""Results as values: the frozen dataclasses that every results file is written from and read back into.

A results file (run.json, study.json, fragility.json, the tune, frontier and explain JSONs, the diagnosis and
outcome diagnosis JSONs, ...) is written from one value, a frozen dataclass whose fields are typed:
:class:`JsonValue` writes it as plain JSON data (:meth:`JsonValue.to_json`) and reads it back by its fields'
type hints (:meth:`JsonValue.from_json`, :func:`read_as`: a missing key takes the field's default), with an
equality under which NaN equals itself. Numbers keep their kind; a non-finite float is written as it is
(:func:`plain`; the run files write it as a string at their edge) or as null (:func:`to_data`, strict JSON).
"""

from __future__ import annotations

import math
import types
import typing
from collections.abc import Mapping
from dataclasses import MISSING, fields, is_dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pandas as pd

__all__ = [
    "JsonValue",
    "WrittenAsResult",
    "floats",
    "json_number",
    "plain",
    "read_as",
    "read_fields",
    "same",
    "to_data",
]


def json_number(x: Any) -> float:
    """A number from a results file, where non-finite floats are written as strings ("inf", "nan") or null."""
    if isinstance(x, str) and x.strip().lower() in ("overturn", "overturned"):
        return math.inf
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def _number(x: Any) -> float:
    """A number as written: an integer stays one (10 is written 10, not 10.0), anything else through
    :func:`json_number`."""
    if isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x)
    return json_number(x)


def same(a: Any, b: Any) -> bool:
    """Equal as results: NaN equals NaN, a list its tuple, tables column by column, values by their fields."""
    if isinstance(a, (float, np.floating)) and isinstance(b, (float, np.floating)):
        return bool(a == b) or (math.isnan(a) and math.isnan(b))
    if isinstance(a, pd.DataFrame) or isinstance(b, pd.DataFrame):
        if not (isinstance(a, pd.DataFrame) and isinstance(b, pd.DataFrame)):
            return False
        if list(a.columns) != list(b.columns) or len(a) != len(b):
            return False
        return all(same(a[c].tolist(), b[c].tolist()) for c in a.columns)
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return same(np.asarray(a).tolist(), np.asarray(b).tolist())
    if isinstance(a, JsonValue) or isinstance(b, JsonValue):
        return type(a) is type(b) and a == b
    return bool(a == b)


def plain(v: Any) -> Any:
    """``v`` as JSON data: a value by its :meth:`~JsonValue.to_json` (or ``to_dict``), tuples as lists, tables
    as their columns."""
    if isinstance(v, JsonValue):
        return v.to_json()
    if hasattr(v, "to_dict") and not isinstance(v, (pd.DataFrame, pd.Series, Mapping)):
        return v.to_dict()
    if isinstance(v, pd.DataFrame):
        return v.to_dict(orient="list")
    if isinstance(v, Mapping):
        return {k: plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    return v


def to_data(value: Any) -> Any:
    """``value`` as strict JSON data (the diagnosis JSONs'): a value by its :meth:`~JsonValue.to_json`, another
    dataclass field by field, tuples and arrays as lists, numpy scalars as Python numbers, paths as text, and
    non-finite floats as None (a file that writes a missing number as null)."""
    if isinstance(value, JsonValue):
        return to_data(value.to_json())
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_data(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, dict):
        return {str(k): to_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [to_data(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, Path):
        return str(value)
    return value


def floats(data: Mapping, *keys: str) -> dict[str, float]:
    """The numbers ``keys`` of ``data`` read as floats (null: NaN), for a ``from_json`` written by hand."""
    return {k: read_as(float, data[k]) for k in keys}


_HINTS: dict[type, dict[str, Any]] = {}


def _hints(cls: type) -> dict[str, Any]:
    if cls not in _HINTS:
        _HINTS[cls] = typing.get_type_hints(cls)
    return _HINTS[cls]


def _fits(tp: Any, x: Any) -> bool:
    """Whether ``x`` is read as type ``tp`` of a union (``float | str``: a number, or a word such as "overturn")."""
    origin = typing.get_origin(tp) or tp
    if origin is float:
        return isinstance(x, (int, float)) and not isinstance(x, bool)
    if isinstance(origin, type) and issubclass(origin, JsonValue):
        return isinstance(x, Mapping)
    return isinstance(x, origin) if isinstance(origin, type) else True


def read_as(tp: Any, x: Any) -> Any:
    """JSON data ``x`` read as type ``tp`` (a field's hint): numbers, words, values (and other dataclasses, by
    their ``from_dict`` or :func:`read_fields`), tuples, lists and tables of them.

    Lenient, as a reader of earlier files must be: null or a table of another shape gives the type's empty
    value (NaN, "", an empty tuple or table) rather than an error.
    """
    if tp is Any:
        return x
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if x is None:
            return None
        kinds = [a for a in args if a is not type(None)]
        return read_as(next((a for a in kinds if _fits(a, x)), kinds[0]), x)
    if isinstance(tp, type) and issubclass(tp, JsonValue):
        return tp.from_json(x)
    if isinstance(tp, type) and hasattr(tp, "from_dict") and not issubclass(tp, (dict, list, tuple)):
        return tp.from_dict(x)
    if isinstance(tp, type) and is_dataclass(tp):
        return read_fields(tp, x)
    if tp is float:
        return _number(x)
    if tp is int:
        v = _number(x)
        return int(v) if isinstance(v, int) or math.isfinite(v) else 0
    if tp is bool:
        return bool(x)
    if tp is str:
        return "" if x is None else str(x)
    if origin is tuple:
        items = list(x) if isinstance(x, (list, tuple)) else []
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(read_as(args[0], v) for v in items)
        return tuple(read_as(a, v) for a, v in zip(args, items, strict=False))
    if origin is list:
        return [read_as(args[0], v) for v in (x if isinstance(x, (list, tuple)) else [])]
    if origin in (dict, Mapping) or tp in (dict, Mapping):
        d = x if isinstance(x, Mapping) else {}
        if not args:
            return dict(d)
        kt, vt = args
        key = {int: lambda k: int(float(k)), float: float}.get(kt, lambda k: k)
        return {key(k): read_as(vt, v) for k, v in d.items()}
    if tp in (list, tuple):
        return tp(x) if isinstance(x, (list, tuple)) else tp()
    return x


class JsonValue:
    """A frozen dataclass written to a results file and read back from it (module docstring).

    Subclasses are ``@dataclass(frozen=True, eq=False)``: equality is this class's (NaN equal to NaN).
    A field named ``extra`` keeps the keys of a file this version does not know, written after the
    fields. A field whose value is None is left out of :meth:`to_json`, except those named in
    :attr:`_ALWAYS` (written as null, as the file always held them) or in :attr:`_EMPTY_WHEN_NONE` (a table not
    measured, written as an empty one); a field of :attr:`_NULL_IS_NAN` reads null as NaN.
    """

    #: Fields written even when None.
    _ALWAYS: ClassVar[tuple[str, ...]] = ()
    #: Optional numbers (``float | None``) whose key, when present, holds a number: null there is NaN (a file that
    #: writes a missing number as null), None only where the key is absent.
    _NULL_IS_NAN: ClassVar[tuple[str, ...]] = ()
    #: Tables written as an empty one (``{}``) when None (not measured), and read back as None when empty.
    _EMPTY_WHEN_NONE: ClassVar[tuple[str, ...]] = ()

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(same(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))

    __hash__ = None  # type: ignore[assignment]

    def to_json(self) -> dict:
        """The value as JSON data: its fields in order (None left out unless in :attr:`_ALWAYS`), then ``extra``."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "extra" or (v is None and f.name not in self._ALWAYS + self._EMPTY_WHEN_NONE):
                continue
            out[f.name] = {} if v is None and f.name in self._EMPTY_WHEN_NONE else plain(v)
        out.update(getattr(self, "extra", None) or {})
        return out

    @classmethod
    def from_json(cls, data: Any):
        """The value of JSON data written by :meth:`to_json` (or by an earlier version: a missing key takes the
        field's default, a key of no field goes to ``extra`` when the class keeps one)."""
        if isinstance(data, cls):
            return data
        return read_fields(cls, data)


def read_fields(cls: type, data: Any) -> Any:
    """The dataclass ``cls`` read from JSON data field by field, by the fields' type hints (:func:`read_as`), with
    the options of :class:`JsonValue` where ``cls`` sets them. A missing key takes the field's default, or the
    empty value of its type."""
    data = data if isinstance(data, Mapping) else {}
    hints = _hints(cls)
    empty_when_none, null_is_nan = getattr(cls, "_EMPTY_WHEN_NONE", ()), getattr(cls, "_NULL_IS_NAN", ())
    kwargs, known = {}, set()
    for f in fields(cls):
        if f.name == "extra" or not f.init:
            continue
        known.add(f.name)
        if f.name in data:
            v = data[f.name]
            if f.name in empty_when_none and not v:
                kwargs[f.name] = None
            elif v is None and f.name in null_is_nan:
                kwargs[f.name] = math.nan
            else:
                kwargs[f.name] = read_as(hints[f.name], v)
        elif f.default is MISSING and f.default_factory is MISSING:
            kwargs[f.name] = read_as(hints[f.name], None)
    if "extra" in {f.name for f in fields(cls)}:
        kwargs["extra"] = {k: v for k, v in data.items() if k not in known}
    return cls(**kwargs)


class WrittenAsResult:
    """An object whose JSON is that of its value ``result()`` (a :class:`JsonValue`): a computation's outcome that
    holds more than its file (the records, the comparisons) and writes what its file holds."""

    def result(self) -> JsonValue:
        raise NotImplementedError

    def to_json(self) -> dict:
        """The JSON's data (:meth:`result`'s)."""
        return self.result().to_json()
