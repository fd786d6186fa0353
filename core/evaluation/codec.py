"""Evaluation reports to and from JSON-ready values, for files that outlive the process that
evaluated (`fusionscope sweep`'s results file).

`encode` is `dataclasses.asdict`. `decode(cls, data)` rebuilds an instance of the dataclass
`cls` by walking its fields' types: nested dataclasses, `X | None`, `tuple[X, ...]`, fixed
tuples such as `tuple[str, X]`, `dict[str, X]`, `list[X]`, `Literal[...]`, int, float (an
integer is taken), str and bool. A field missing from `data` takes its default, so a file
written before a field with a default was added still reads. What does not fit raises
CodecError naming the place, e.g. `vehicles.fn_at[3][1]: expected an integer, got 'x'`.
`empty(cls)` is an instance with every field zero or empty.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from typing import Any, TypeVar

T = TypeVar("T")

MAX_SHOWN = 80  # characters of a wrong value quoted in an error


class CodecError(ValueError):
    """Data that is not the encoding of the expected dataclass; the message names the field."""


def encode(value: object) -> dict[str, Any]:
    """A dataclass instance as nested dicts, lists and plain values (`json.dumps`-ready)."""
    if not dataclasses.is_dataclass(value) or isinstance(value, type):
        raise TypeError(f"encode: expected a dataclass instance, got {type(value).__name__}")
    return dataclasses.asdict(value)


def decode(cls: type[T], data: object, where: str = "") -> T:
    """The instance of dataclass `cls` that `encode` turned into `data`; `where` prefixes the
    place named in a CodecError."""
    return typing.cast(T, _decode(cls, data, where))


def empty(cls: type[T]) -> T:
    """An instance of dataclass `cls` with every field zero: numbers 0, strings "", tuples,
    lists and dicts empty, `X | None` None, dataclasses empty; fields with a default keep it."""
    kind: Any = cls  # a dataclass: fields() and the hints' cache take it
    values: dict[str, Any] = {}
    hints = _hints(kind)
    for f in dataclasses.fields(kind):
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            values[f.name] = _zero(hints[f.name])
    return cls(**values)


@functools.cache
def _hints(cls: Any) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _zero(tp: Any) -> object:
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp) and isinstance(tp, type):
        return empty(tp)
    if origin in (typing.Union, types.UnionType) and type(None) in typing.get_args(tp):
        return None
    if origin is tuple:
        return ()
    if origin is list:
        return []
    if origin is dict:
        return {}
    if tp in (int, float, str, bool):
        return tp()
    raise TypeError(f"empty: no zero for the type {tp!r}")


def _where(where: str, part: str) -> str:
    return f"{where}.{part}" if where else part


def _fail(where: str, expected: str, got: object) -> CodecError:
    text = repr(got)
    if len(text) > MAX_SHOWN:
        text = text[: MAX_SHOWN - 3] + "..."
    return CodecError(f"{where or 'value'}: expected {expected}, got {text}")


def _decode(tp: Any, raw: object, where: str) -> object:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if dataclasses.is_dataclass(tp) and isinstance(tp, type):
        return _decode_dataclass(tp, raw, where)
    if origin in (typing.Union, types.UnionType):
        if raw is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        for option in options[:-1]:
            try:
                return _decode(option, raw, where)
            except CodecError:
                continue
        return _decode(options[-1], raw, where)
    if origin is tuple:
        if not isinstance(raw, (list, tuple)):
            raise _fail(where, "a list", raw)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_decode(args[0], item, f"{where}[{k}]") for k, item in enumerate(raw))
        if len(raw) != len(args):
            raise _fail(where, f"a list of {len(args)} items", raw)
        return tuple(
            _decode(a, item, f"{where}[{k}]")
            for k, (a, item) in enumerate(zip(args, raw, strict=True))
        )
    if origin is list:
        if not isinstance(raw, (list, tuple)):
            raise _fail(where, "a list", raw)
        return [_decode(args[0], item, f"{where}[{k}]") for k, item in enumerate(raw)]
    if origin is dict:
        if not isinstance(raw, dict):
            raise _fail(where, "a mapping", raw)
        out = {}
        for key, value in raw.items():
            out[_decode(args[0], key, where)] = _decode(args[1], value, _where(where, str(key)))
        return out
    if origin is typing.Literal:
        if raw not in args:
            raise _fail(where, f"one of {', '.join(map(repr, args))}", raw)
        return raw
    if tp is bool:
        if not isinstance(raw, bool):
            raise _fail(where, "true or false", raw)
        return raw
    if tp is int:
        if not isinstance(raw, int) or isinstance(raw, bool):
            raise _fail(where, "an integer", raw)
        return raw
    if tp is float:
        if not isinstance(raw, (int, float)) or isinstance(raw, bool):
            raise _fail(where, "a number", raw)
        return float(raw)
    if tp is str:
        if not isinstance(raw, str):
            raise _fail(where, "a string", raw)
        return raw
    if tp is Any or tp is object:
        return raw
    raise TypeError(f"decode: unsupported field type {tp!r} at {where or 'the top'}")


def _decode_dataclass(cls: type, raw: object, where: str) -> object:
    if not isinstance(raw, dict):
        raise _fail(where, f"a mapping of {cls.__name__}'s fields", raw)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(raw) - set(fields), key=str)
    if unknown:
        raise CodecError(
            f"{_where(where, str(unknown[0]))}: not a field of {cls.__name__}; "
            f"its fields: {', '.join(fields)}"
        )
    hints = _hints(cls)
    values = {}
    for name, f in fields.items():
        if name in raw:
            values[name] = _decode(hints[name], raw[name], _where(where, name))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise CodecError(f"{_where(where, name)}: missing ({cls.__name__} needs it)")
    return cls(**values)
