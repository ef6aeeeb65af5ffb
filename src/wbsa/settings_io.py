"""TOML tables ⇄ frozen settings dataclasses, for any stage's settings.

One small generic layer: :func:`from_table` builds a settings dataclass from a TOML table (as
:mod:`tomllib` returns it), checking keys and types against the dataclass's annotations;
:func:`to_table` turns a settings object back into such a table; :func:`dump_toml` writes tables
as TOML text that :mod:`tomllib` reads back.

Mapping rules
-------------
- A key is a field name; a key left out keeps the field's default.
- ``bool``, ``int``, ``float``, ``str`` and ``Literal[...]`` fields take the TOML value of that type
  (an integer is accepted for a float).
- ``tuple[X, ...]`` and ``tuple[X, Y]`` fields take TOML arrays.
- A field that is itself a settings dataclass is a sub-table (``[fit.group_spec]``).
- ``X | None`` fields: TOML has no null, so *leaving the key out* means None (when None is the
  default); :func:`to_table` leaves None values out.

Errors name the file, the table and the key: a wrong type gives ``must be ...``; the dataclass's own
checks raise :class:`~wbsa.errors.SettingsError` naming the field, and become one-line
:class:`~wbsa.errors.WbsaError` messages such as ``study.toml: [fit] k must be at least 2 folds, got 1``.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any, Literal, TypeVar, Union, get_args, get_origin

from wbsa.errors import SettingsError, WbsaError

T = TypeVar("T")


class _TypeMismatch(Exception):
    """A TOML value of the wrong type (the message is 'must be ...')."""


def from_table(cls: type[T], table: dict, section: str, source: str = "<dict>") -> T:
    """Build settings ``cls`` from one TOML table.

    Parameters
    ----------
    cls : dataclass type
        A frozen settings dataclass whose fields have the types listed in the module doc.
    table : dict
        ``{key: value}`` as :mod:`tomllib` returns it.
    section : str
        Name of the table for messages (``fit``; a sub-table is ``fit.group_spec``).
    source : str
        Name of the file (or ``<dict>``) for messages.

    Returns
    -------
    cls instance

    Raises
    ------
    WbsaError
        One line naming ``source``, ``[section]`` and the key: an unknown key, a wrong type, or a
        value the dataclass rejects.
    """
    if not isinstance(table, dict):
        raise WbsaError(f"{source}: {section} must be a table ([{section}] with keys), not a single value")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = [k for k in table if k not in names]
    if unknown:
        raise WbsaError(f"{source}: unknown key {unknown[0]!r} in [{section}]; valid keys: {', '.join(names)}")
    kwargs = {}
    for key, value in table.items():
        nested = _dataclass_of(hints[key])
        if nested is not None:
            kwargs[key] = from_table(nested, value, f"{section}.{key}", source)
            continue
        try:
            kwargs[key] = _coerce(value, hints[key])
        except _TypeMismatch as exc:
            raise WbsaError(f"{source}: [{section}] {key} {exc}") from None
    try:
        return cls(**kwargs)
    except WbsaError as exc:  # a SettingsError's message starts with the field
        raise WbsaError(f"{source}: [{section}] {exc}") from None


def to_table(settings: Any, keep_none: bool = False) -> dict[str, Any]:
    """A settings dataclass as a TOML-ready table: tuples as lists, sub-dataclasses as sub-tables.

    None values are left out (TOML has no null), or kept with ``keep_none`` (:func:`dump_toml` then
    writes them as comments, so a written file still shows every key).
    """
    out: dict[str, Any] = {}
    for f in dataclasses.fields(settings):
        value = _plain(getattr(settings, f.name), keep_none)
        if value is not None or keep_none:
            out[f.name] = value
    return out


def field_defaults(cls: type) -> dict[str, Any]:
    """The default of every field of settings class ``cls`` that has one (for help texts of CLI flags).

    Works for classes whose defaults alone are not a valid instance (a population has no default size).
    """
    out = {}
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
    return out


def dump_toml(tables: dict[str, dict[str, Any]], header: str = "") -> str:
    """Write ``{table: {key: value}}`` as TOML text that :mod:`tomllib` reads back.

    Values are scalars, lists of scalars (or of lists), or dicts, which become sub-tables
    (``[table.key]``) after the table's own keys. A None value becomes the comment ``# key: not set``.
    """
    lines = [f"# {header}", ""] if header else []
    for name, table in tables.items():
        lines += _dump_table(name, table)
    return "\n".join(lines)


def _dump_table(name: str, table: dict[str, Any]) -> list[str]:
    lines = [f"[{name}]"]
    lines += [f"# {k}: not set" if v is None else f"{k} = {_toml_value(v)}"
              for k, v in table.items() if not isinstance(v, dict)]
    lines.append("")
    for k, v in table.items():
        if isinstance(v, dict):
            lines += _dump_table(f"{name}.{k}", v)
    return lines


def _plain(obj: Any, keep_none: bool = False) -> Any:
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return to_table(obj, keep_none)
    if isinstance(obj, (tuple, list)):
        return [_plain(v, keep_none) for v in obj]
    return obj


def _dataclass_of(tp: Any) -> type | None:
    """The dataclass type of a field annotated with one (``X`` or ``X | None``), else None."""
    if get_origin(tp) in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        tp = args[0] if len(args) == 1 else None
    return tp if isinstance(tp, type) and dataclasses.is_dataclass(tp) else None


def type_name(tp: Any) -> str:
    """How a field type reads in a message: ``an integer``, ``one of 'a', 'b'``, ``a list of a number``."""
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        return " or ".join(type_name(a) for a in args)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(tp))
    if origin is tuple:
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"a list of {type_name(args[0])}"
        return f"a list of {len(args)} values ({', '.join(type_name(a) for a in args)})"
    names = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}
    return names.get(tp, f"a {tp.__name__}" if isinstance(tp, type) else str(tp))


def _coerce(value: Any, tp: Any) -> Any:
    """``value`` (from TOML) as type ``tp``; raises :class:`_TypeMismatch` with 'must be ...'."""
    origin = get_origin(tp)
    bad = _TypeMismatch(f"must be {type_name(tp)}, got {value!r}")
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return _coerce(value, args[0])
        for arg in args:  # the first of the choices that takes it
            try:
                return _coerce(value, arg)
            except _TypeMismatch:
                pass
        raise bad
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):  # a record given whole (a camera's, from Python)
        if not isinstance(value, tp):
            raise bad
        return value
    if origin is Literal:
        if value not in get_args(tp):
            raise bad
        return value
    if origin is tuple:
        if not isinstance(value, list):
            raise bad
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_coerce(v, args[0]) for v in value)
        if len(value) != len(args):
            raise bad
        return tuple(_coerce(v, a) for v, a in zip(value, args))
    if tp is bool:
        if not isinstance(value, bool):
            raise bad
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise bad
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise bad
        return value
    raise bad  # a field type this layer does not map (a settings class would not use it)


def check_types(settings: Any) -> None:
    """Check every field of a settings dataclass against its annotation, for values given from Python.

    The same rules as for TOML values (:func:`from_table`), so ``FitSettings(k="3")`` fails like ``k = "3"``
    in a study file. Values are normalised in place: lists become tuples, integers in float fields become
    floats, NumPy scalars become Python numbers. Nested settings and ``None`` for optional fields pass.
    Call it first in a settings class's ``__post_init__``.

    Raises
    ------
    SettingsError
        Naming the first field of the wrong type: ``k must be an integer, got '3'``.
    """
    hints = typing.get_type_hints(type(settings))
    for f in dataclasses.fields(settings):
        value, tp = getattr(settings, f.name), hints[f.name]
        if value is None and type(None) in get_args(tp):
            continue
        if dataclasses.is_dataclass(value) and _dataclass_of(tp) is type(value):
            continue
        try:
            new = _coerce(_as_toml(value), tp)
        except _TypeMismatch as exc:
            raise SettingsError(f.name, str(exc)) from None
        if type(new) is not type(value) or new != value:
            object.__setattr__(settings, f.name, new)


def _as_toml(value: Any) -> Any:
    """A Python value as TOML would give it: sequences as lists, NumPy scalars as Python scalars."""
    if isinstance(value, (tuple, list)):
        return [_as_toml(v) for v in value]
    if hasattr(value, "item") and getattr(value, "shape", None) == ():  # a NumPy scalar
        return value.item()
    return value


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")
