"""Declarative field specifications and the generic table reader.

A section of a mechanism file (a body, a joint of one type, ``[simulation]``)
is described by a mapping ``key -> Field``; `read_table` checks a parsed TOML
table against it and returns the converted values.  Every error names the
file, the key path (``joints[2].point_i``, indices from 0 in file order), what
is wrong and what is allowed:

    model.toml: joints[2].point_i: '3 kg' ...; allowed: ...

Order of the checks in one table: unknown keys (with a difflib suggestion)
first, since a misspelt key is the usual cause of a "missing" one; then
each field in declaration order.
"""

from __future__ import annotations

import datetime
import difflib
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import InputError
from . import units


class _Required:
    def __repr__(self):
        return "REQUIRED"


REQUIRED: Any = _Required()
"""Default of a field that must be given."""

NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,63}")
"""Names of bodies, joints and forces: they become file and column names
(``reaction_<joint>.csv``, ``<body>_x_m``)."""
NAME_RULE = "ASCII: a letter A-Z or a-z, then up to 63 such letters, digits, '_' or '-'"


def toml_type(value) -> str:
    """The TOML name of a parsed value's type, for messages."""
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    if isinstance(value, dict):
        return "table"
    if isinstance(value, (datetime.date, datetime.time)):
        return "date/time"
    return type(value).__name__


def show(value) -> str:
    """A value as the user wrote it (shortened)."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def suggest(word: str, candidates: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest candidate (difflib ratio >= 0.6,
    or equal ignoring case), else ``""``."""
    close = [c for c in candidates if c.lower() == word.lower()]
    close = close or difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


@dataclass
class Context:
    """Where we are: the file name (for messages) and the names known so far."""

    file: str
    bodies: tuple[str, ...] = ()

    def error(self, path: str, what: str, allowed: str | None = None) -> InputError:
        tail = f"; allowed: {allowed}" if allowed else ""
        return InputError(f"{self.file}: {path}: {what}{tail}")

    def wrap(self, path: str, err: InputError) -> InputError:
        """Prefix a message from a units or model check with the file and path."""
        return InputError(f"{self.file}: {path}: {err}")


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


# ----------------------------------------------------------------------------- fields
@dataclass(frozen=True)
class Field:
    """One key of a table.  ``spellings(key)`` lists the accepted key names."""

    default: Any = REQUIRED
    doc: str = ""

    def spellings(self, key: str) -> tuple[str, ...]:
        return (key,)

    def expects(self, key: str) -> str:
        """What a valid value looks like (for 'missing' and type errors)."""
        raise NotImplementedError

    def read(self, ctx: Context, path: str, key: str, spelling: str, raw) -> Any:
        """Converted value of ``raw`` given under ``spelling`` (one of ``spellings(key)``)."""
        raise NotImplementedError


def _check_bounds(ctx, path, shown, value, *, low, high, low_open, high_open, unit=""):
    if low is None and high is None:
        return
    lo = -math.inf if low is None else low
    hi = math.inf if high is None else high
    bad_low = value <= lo if low_open else value < lo
    bad_high = value >= hi if high_open else value > hi
    if bad_low or bad_high:
        if high is None:
            interval = f"{'>' if low_open else '>='} {lo:g}"
        elif low is None:
            interval = f"{'<' if high_open else '<='} {hi:g}"
        else:
            interval = f"{'(' if low_open else '['}{lo:g}, {hi:g}{')' if high_open else ']'}"
        u = f" {unit}" if unit else ""
        got = f"{shown} = {value:g}{u}" if shown != repr(value) else shown
        raise ctx.error(path, f"{got} is out of range", f"{interval}{u}")


@dataclass(frozen=True)
class Text(Field):
    """A string; ``name=True`` restricts it to `NAME_PATTERN`; ``choices`` to a set."""

    name: bool = False
    choices: tuple[str, ...] = ()

    def expects(self, key):
        if self.choices:
            return " | ".join(repr(c) for c in self.choices)
        return f"a name: {NAME_RULE}" if self.name else "a string"

    def read(self, ctx, path, key, spelling, raw):
        if not isinstance(raw, str):
            raise ctx.error(path, f"expected a string, got {toml_type(raw)} {show(raw)}",
                            self.expects(key))
        if self.choices and raw not in self.choices:
            raise ctx.error(path, f"{raw!r} is not allowed{suggest(raw, self.choices)}",
                            self.expects(key))
        if self.name and NAME_PATTERN.fullmatch(raw) is None:
            raise ctx.error(path, f"{raw!r} is not a valid name", NAME_RULE)
        return raw


@dataclass(frozen=True)
class BodyRef(Field):
    """The name of a body of ``[[bodies]]`` (or ``"ground"`` if ``ground``)."""

    ground: bool = True

    def _names(self, ctx):
        return (*ctx.bodies, "ground") if self.ground else ctx.bodies

    def expects(self, key):
        return "a body name from [[bodies]]" + (' or "ground"' if self.ground else "")

    def read(self, ctx, path, key, spelling, raw):
        names = self._names(ctx)
        if not isinstance(raw, str):
            raise ctx.error(path, f"expected a body name (string), got {toml_type(raw)} "
                            f"{show(raw)}", ", ".join(names))
        if raw not in names:
            what = ("the ground cannot be used here" if raw == "ground"
                    else f"unknown body {raw!r}{suggest(raw, names)}")
            raise ctx.error(path, what, ", ".join(names))
        return raw


@dataclass(frozen=True)
class Quantity(Field):
    """A dimensioned scalar: ``key = "20 mm"`` or ``key_<unit> = 0.02``-style."""

    dimension: str = "length"
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def spellings(self, key):
        unit_names = units.DIMENSIONS[self.dimension].units
        return (key, *(f"{key}_{units.key_suffix(u)}" for u in unit_names))

    def expects(self, key):
        dim = units.DIMENSIONS[self.dimension]
        suffix = units.key_suffix(dim.si)
        return (f"{key} = \"<number> <unit>\" with a {self.dimension} unit "
                f"({units.allowed_units(self.dimension)}), e.g. {key} = {dim.example!r}, "
                f"or a plain number under a key naming the unit, e.g. {key}_{suffix}")

    def _unit_of(self, key, spelling):
        for u in units.DIMENSIONS[self.dimension].units:
            if spelling == f"{key}_{units.key_suffix(u)}":
                return u
        return None

    def read(self, ctx, path, key, spelling, raw):
        unit = self._unit_of(key, spelling) if spelling != key else None
        dim = units.DIMENSIONS[self.dimension]
        if unit is None and _is_number(raw):
            raise ctx.error(
                path, f"bare number {raw!r} has no unit (units are never guessed)",
                f"a string such as \"{raw} {dim.si}\" or the key "
                f"{key}_{units.key_suffix(dim.si)} = {raw}; {self.dimension} units: "
                f"{units.allowed_units(self.dimension)}")
        if unit is None and not isinstance(raw, str):
            raise ctx.error(path, f"expected a string with a unit, got {toml_type(raw)} "
                            f"{show(raw)}", self.expects(key))
        if unit is not None and not _is_number(raw):
            raise ctx.error(path, f"the key names the unit {unit!r}, so the value must be a plain "
                            f"number, got {toml_type(raw)} {show(raw)}",
                            f"{spelling} = <number>, or {key} = \"<number> {unit}\"")
        try:
            value = (units.parse_quantity(raw, self.dimension) if unit is None
                     else units.to_si(raw, unit, self.dimension))
        except InputError as err:
            raise ctx.wrap(path, err) from None
        si = units.DIMENSIONS[self.dimension].si
        _check_bounds(ctx, path, show(raw), value, low=self.low, high=self.high,
                      low_open=self.low_open, high_open=self.high_open, unit=si)
        return value


@dataclass(frozen=True)
class Vector(Field):
    """A 2-vector of one dimension: ``["-1 m", "0 m"]`` or ``key_m = [-1, 0]``."""

    dimension: str = "length"

    def spellings(self, key):
        return Quantity(dimension=self.dimension).spellings(key)

    def expects(self, key):
        dim = units.DIMENSIONS[self.dimension]
        return (f"two {self.dimension}s [x, y] such as {key} = [{dim.example!r}, {dim.example!r}] "
                f"(units: {units.allowed_units(self.dimension)}), or plain numbers under a key "
                f"naming the unit, e.g. {key}_{units.key_suffix(dim.si)} = [0.0, 0.0]")

    def read(self, ctx, path, key, spelling, raw):
        if not isinstance(raw, list) or len(raw) != 2:
            if isinstance(raw, list):
                got = f"an array of {len(raw)} value{'' if len(raw) == 1 else 's'}"
            else:
                got = f"{toml_type(raw)} {show(raw)}"
            raise ctx.error(path, f"expected an array of 2 values [x, y], got {got}",
                            self.expects(key))
        q = Quantity(dimension=self.dimension)
        return tuple(q.read(ctx, f"{path}[{k}]", key, spelling, v) for k, v in enumerate(raw))


@dataclass(frozen=True)
class Direction(Field):
    """A dimensionless, non-zero 2-vector (e.g. a sliding axis), plain numbers."""

    def expects(self, key):
        return f"two plain numbers, not both zero, e.g. {key} = [1.0, 0.0]"

    def read(self, ctx, path, key, spelling, raw):
        if not isinstance(raw, list) or len(raw) != 2 or not all(_is_number(v) for v in raw):
            raise ctx.error(path, f"expected an array of 2 numbers, got {toml_type(raw)} "
                            f"{show(raw)}", self.expects(key))
        if not all(math.isfinite(v) for v in raw):
            raise ctx.error(path, f"{show(raw)} is not finite", self.expects(key))
        if not any(raw):
            raise ctx.error(path, "the direction is the zero vector", self.expects(key))
        return (float(raw[0]), float(raw[1]))


@dataclass(frozen=True)
class Number(Field):
    """A dimensionless float (or integer) with optional bounds."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def expects(self, key):
        return "a plain number"

    def read(self, ctx, path, key, spelling, raw):
        if not _is_number(raw):
            raise ctx.error(path, f"expected a number, got {toml_type(raw)} {show(raw)}",
                            self.expects(key))
        if not math.isfinite(raw):
            raise ctx.error(path, f"{raw!r} is not finite", "a finite number")
        _check_bounds(ctx, path, show(raw), float(raw), low=self.low, high=self.high,
                      low_open=self.low_open, high_open=self.high_open)
        return float(raw)


@dataclass(frozen=True)
class Integer(Field):
    """An integer with bounds (``1e3`` is a float in TOML: write ``1000`` or ``1_000``)."""

    low: int | None = None
    high: int | None = None

    def expects(self, key):
        return f"an integer in [{self.low}, {self.high}]"

    def read(self, ctx, path, key, spelling, raw):
        if isinstance(raw, bool) or not isinstance(raw, int):
            hint = ""
            if isinstance(raw, float) and math.isfinite(raw) and raw == int(raw):
                hint = f" (write {int(raw)} without a decimal point or exponent)"
            raise ctx.error(path, f"expected an integer, got {toml_type(raw)} {show(raw)}{hint}",
                            self.expects(key))
        _check_bounds(ctx, path, show(raw), raw, low=self.low, high=self.high,
                      low_open=False, high_open=False)
        return raw


@dataclass(frozen=True)
class Table(Field):
    """An inline sub-table with its own fields: ``friction = { coefficient = 0.13 }``."""

    fields: Mapping[str, Field] = None  # type: ignore[assignment]

    def expects(self, key):
        return "{ " + ", ".join(self.fields) + " }"

    def read(self, ctx, path, key, spelling, raw):
        return read_table(ctx, path, raw, self.fields, self.expects(key))


@dataclass(frozen=True)
class Tagged(Field):
    """A sub-table whose ``type`` key picks its fields:
    ``law = { type = "kelvin-voigt", stiffness = "1e8 N/m" }``.  Returns the
    converted fields plus ``"type"``."""

    types: Mapping[str, Mapping[str, Field]] = None  # type: ignore[assignment]
    what: str = "type"

    def expects(self, key):
        return f"{{ type = {' | '.join(repr(t) for t in self.types)}, ... }}"

    def read(self, ctx, path, key, spelling, raw):
        table = check_table(ctx, path, raw, self.expects(key))
        kind = read_type_tag(ctx, path, table, self.types, self.what)
        rest = {k: v for k, v in table.items() if k != "type"}
        return {"type": kind, **read_table(ctx, path, rest, self.types[kind])}


def read_type_tag(ctx: Context, path: str, table: dict, types: Mapping, what: str,
                  hint: str = "") -> str:
    """The table's ``type`` key, checked against ``types`` (with a did-you-mean
    suggestion; ``hint`` is appended to the unknown-type message)."""
    kinds = ", ".join(repr(t) for t in types)
    kind = table.get("type")
    if kind is None:
        raise ctx.error(f"{path}.type", "missing key", kinds)
    if not isinstance(kind, str):
        raise ctx.error(f"{path}.type",
                        f"expected a string, got {toml_type(kind)} {show(kind)}", kinds)
    if kind not in types:
        raise ctx.error(f"{path}.type",
                        f"unknown {what} {kind!r}{suggest(kind, list(types))}{hint}", kinds)
    return kind


# ----------------------------------------------------------------------------- tables
def check_table(ctx: Context, path: str, raw, what: str) -> dict:
    if not isinstance(raw, dict):
        raise ctx.error(path, f"expected a table ({what}), got {toml_type(raw)} {show(raw)}")
    return raw


def check_unknown(ctx: Context, path: str, table: Mapping, allowed: Sequence[str],
                  suggestions: Sequence[str] | None = None, hint: str = "") -> None:
    """Raise for the first key of ``table`` not in ``allowed``."""
    for key in table:
        if key not in allowed:
            where = f"{path}.{key}" if path else key
            shown = ", ".join(suggestions or allowed)
            raise ctx.error(where, f"unknown key {key!r}{suggest(key, list(allowed))}",
                            shown + hint)


def read_table(ctx: Context, path: str, table, fields: Mapping[str, Field],
               what: str = "") -> dict[str, Any]:
    """Validate ``table`` against ``fields``; returns ``{key: converted value}``."""
    table = check_table(ctx, path, table, what or "key = value pairs")
    spelling_of = {s: k for k, f in fields.items() for s in f.spellings(k)}
    dimensioned = [s for k, f in fields.items() for s in f.spellings(k)[1:2]]
    check_unknown(ctx, path, table, list(spelling_of), list(fields),
                  f" (dimensioned keys also as <key>_<unit>, e.g. {dimensioned[0]})"
                  if dimensioned else "")
    values: dict[str, Any] = {}
    for key, spec in fields.items():
        given = [s for s in spec.spellings(key) if s in table]
        where = f"{path}.{key}" if path else key
        if len(given) > 1:
            raise ctx.error(where, f"given twice, as {' and '.join(given)}", "exactly one of them")
        if not given:
            if spec.default is REQUIRED:
                raise ctx.error(where, "missing key", spec.expects(key))
            values[key] = spec.default
            continue
        spelling = given[0]
        where = f"{path}.{spelling}" if path else spelling
        values[key] = spec.read(ctx, where, key, spelling, table[spelling])
    return values


def read_array_of_tables(ctx: Context, key: str, raw, *, required: bool) -> list[dict]:
    """``[[key]]`` entries as a list of tables (``[]`` when absent and optional)."""
    if raw is None:
        if required:
            raise ctx.error(key, "missing section", f"one or more [[{key}]] tables")
        return []
    if isinstance(raw, dict):
        raise ctx.error(key, f"[{key}] is a single table", f"an array of tables: write [[{key}]]")
    if not isinstance(raw, list):
        raise ctx.error(key, f"expected an array of tables [[{key}]], got {toml_type(raw)} "
                        f"{show(raw)}", f"[[{key}]] tables")
    for k, item in enumerate(raw):
        check_table(ctx, f"{key}[{k}]", item, f"one [[{key}]] entry")
    if required and not raw:
        raise ctx.error(key, "is empty", f"one or more [[{key}]] tables")
    return raw


__all__ = [
    "REQUIRED", "NAME_PATTERN", "Context", "Field", "Text", "BodyRef", "Quantity", "Vector",
    "Direction", "Number", "Integer", "Table", "Tagged", "read_table", "read_array_of_tables",
    "check_table", "check_unknown", "toml_type", "show", "suggest",
]
