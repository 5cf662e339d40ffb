"""Typed result values to and from plain JSON data, by their dataclass fields and type hints: what a results JSON
is written from and read back into (``T.from_json(x.to_json()) == x``)."""

from __future__ import annotations

import json
import math
import types
import typing
from dataclasses import MISSING, fields, is_dataclass
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

__all__ = ["JsonValue", "WrittenAsResult", "floats", "from_data", "number", "to_data"]

T = TypeVar("T", bound="JsonValue")


def number(x: Any) -> float | None:
    """A float, or None where there is no finite value (NaN, an infinity, None): a results JSON writes null there."""
    if x is None:
        return None
    v = float(x)
    return v if math.isfinite(v) else None


def floats(data: dict, *keys: str) -> dict[str, float]:
    """The numbers ``keys`` of ``data`` as floats (null: :data:`math.nan`), for a ``from_dict`` written by hand."""
    return {k: from_data(float, data[k]) for k in keys}


def _key(f) -> str:
    return f.metadata.get("json", f.name)


def to_data(value: Any) -> Any:
    """``value`` as plain JSON data: a dataclass field by field (its JSON key is the field's name, or its metadata's
    ``json``; a field whose metadata has ``omit_none`` is left out when None), tuples and arrays as lists, numpy
    scalars as Python numbers, non-finite floats as None."""
    if is_dataclass(value) and not isinstance(value, type):
        out = {}
        for f in fields(value):
            v = getattr(value, f.name)
            if v is None and f.metadata.get("omit_none"):
                continue
            out[_key(f)] = to_data(v)
        return out
    if isinstance(value, dict):
        return {str(k): to_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [to_data(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        return number(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, Path):
        return str(value)
    return value


def from_data(tp: Any, data: Any) -> Any:
    """The value of type ``tp`` that :func:`to_data` wrote as ``data``.

    Dataclasses are read by their type hints (a key the data lacks takes the field's default), ``tuple[X, ...]``,
    ``list[X]`` and ``dict[str, X]`` element by element, ``X | None`` as None or X; ``Any``, ``dict`` and ``list``
    without parameters are plain data, kept as read. A ``float`` written as null (no finite value) reads as
    :data:`math.nan`, one object: what is read back compares equal to itself read again, so a value read from a
    results JSON survives ``from_json(to_json(x)) == x``; a fresh value with a non-finite number does not (the JSON
    keeps no difference between NaN and an infinity).
    """
    if tp is Any or tp is None:
        return data
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if data is None:
            return None
        return from_data(args[0], data) if len(args) == 1 else data
    if is_dataclass(tp):
        hints = typing.get_type_hints(tp)
        kwargs = {}
        for f in fields(tp):
            if not f.init:
                continue
            key = _key(f)
            if key in data:
                kwargs[f.name] = from_data(hints[f.name], data[key])
            elif f.default is MISSING and f.default_factory is MISSING:
                raise ValueError(f"{tp.__name__}: the data has no {key!r}")
        return tp(**kwargs)
    if origin is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(from_data(args[0], v) for v in data)
        return tuple(from_data(a, v) for a, v in zip(args, data, strict=True))
    if origin is list:
        (arg,) = typing.get_args(tp)
        return [from_data(arg, v) for v in data]
    if origin is dict:
        _k, arg = typing.get_args(tp)
        return {k: from_data(arg, v) for k, v in data.items()}
    if tp is float:
        return math.nan if data is None else float(data)
    if tp is int:
        return int(data)
    if tp is bool:
        return bool(data)
    return data


class JsonValue:
    """A frozen dataclass that is a results JSON: :meth:`to_dict` / :meth:`from_dict` (plain data, :func:`to_data`
    and :func:`from_data`), :meth:`to_json` / :meth:`from_json` (its text, strict JSON)."""

    #: The JSON text's indentation.
    JSON_INDENT: ClassVar[int] = 2

    def to_dict(self) -> dict:
        return to_data(self)

    @classmethod
    def from_dict(cls: type[T], data: dict) -> T:
        return from_data(cls, data)

    def to_json(self, path: str | Path | None = None) -> str:
        """The JSON text; also written to ``path`` when given."""
        text = json.dumps(self.to_dict(), indent=self.JSON_INDENT, allow_nan=False)
        if path is not None:
            Path(path).write_text(text + "\n")
        return text

    @classmethod
    def from_json(cls: type[T], text: str) -> T:
        return cls.from_dict(json.loads(text))


class WrittenAsResult:
    """An object whose JSON is that of its value ``result()`` (a :class:`JsonValue`): a computation's outcome that
    holds more than its file (the records, the comparisons) and writes what its file holds."""

    def result(self) -> JsonValue:
        raise NotImplementedError

    def to_dict(self) -> dict:
        """The JSON's data (:meth:`result`'s)."""
        return self.result().to_dict()

    def to_json(self, path: str | Path | None = None) -> str:
        """The JSON's text; also written to ``path`` when given."""
        return self.result().to_json(path)
