"""A small declarative schema for YAML documents.

A schema is a tree of specs (:class:`Section`, :class:`NamedList`, :class:`Number`, ...).
:func:`check` walks a document along it, converts quantities to SI units, fills in
defaults and collects every problem at once, each with the key path where it was found.
The same tree produces the reference table of the scenario format (:func:`reference_rows`),
so the documentation cannot drift from what the loader accepts.

Why one module of more than 400 lines: it is a small self-contained library, one short class
per kind of YAML value (its check, its unit conversion, its reference text) over the shared
:class:`Ctx`, read one class at a time; ``Section`` and ``NamedList`` nest any of them, so the
pieces of a split would import each other back. What tmpnav's scenario *is* lives in format.py.
"""

from __future__ import annotations

import difflib
import math
import reprlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tmpnav.scenario.units import UnitError, parse_quantity, si_unit

MISSING: Any = object()


@dataclass
class Issue:
    """A problem found by the walker: display path, raw path (for line lookup), message."""

    path: str
    raw: tuple[Any, ...]
    message: str


@dataclass
class Ctx:
    """Walk state: issues found so far and the current path (display and raw)."""

    issues: list[Issue] = field(default_factory=list)

    def add(self, path: str, raw: tuple[Any, ...], message: str) -> None:
        self.issues.append(Issue(path, raw, message))


def join(path: str, key: object) -> str:
    """A display key path one level down: ``robots[2]``, ``robots.r1.speed``."""
    if isinstance(key, int):
        return f"{path}[{key}]"
    text = key_text(key)
    return f"{path}.{text}" if path else text


def key_text(key: object, limit: int = 60) -> str:
    """A mapping key as messages show it: control and invisible characters escaped (a
    key must not break the one-line message or hide in it), long keys shortened."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(key))
    return text if len(text) <= limit else text[: limit - 3] + "..."


_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxlist, _SHORT.maxdict, _SHORT.maxstring, _SHORT.maxother = 4, 8, 8, 80, 80


def show(value: object, limit: int = 60) -> str:
    """A value as it appears in messages, shortened when long (in time too: a huge
    nested value is never converted to text whole)."""
    text = _SHORT.repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def as_float(value: int | float) -> float:
    """float(value), with integers beyond the largest float as +-inf (not OverflowError)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


class Spec:
    """Base of all specs: a type description for messages and the reference table."""

    doc: str = ""

    def describe(self) -> str:  # the "expected ..." part of messages
        raise NotImplementedError

    def unit(self) -> str:
        return ""

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        """Return the converted value, or MISSING after recording an issue."""
        raise NotImplementedError


@dataclass
class Number(Spec):
    dimension: str | None = None  # length | angle | time | speed | angular_speed | None
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    integer: bool = False
    reason: str = ""  # why the range ends where it does, for messages

    def bounds(self) -> str:
        """The accepted range: ``> 0``, ``>= 0 and <= 1``, or empty."""

        def fmt(x: float) -> str:
            return str(int(x)) if self.integer else f"{x:g}"

        parts = []
        if self.minimum is not None:
            parts.append(f"{'>' if self.exclusive_minimum else '>='} {fmt(self.minimum)}")
        if self.maximum is not None:
            parts.append(f"<= {fmt(self.maximum)}")
        return " and ".join(parts)

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a number"
        text = kind + (f" {self.bounds()}" if self.bounds() else "")
        if self.dimension:
            text += f" in {si_unit(self.dimension)} (or a string such as '1.5 {si_unit(self.dimension)}')"
        if self.reason:
            text += f"; {self.reason}"
        return text

    def unit(self) -> str:
        return si_unit(self.dimension)

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        try:
            number = parse_quantity(value, self.dimension)
        except UnitError as err:
            ctx.add(path, raw, f"{show(value)} {err}; expected {self.describe()}")
            return MISSING
        if not math.isfinite(number):
            ctx.add(path, raw, f"{show(value)} is not finite; expected {self.describe()}")
            return MISSING
        # an integer may be written 1e3 (a float in YAML 1.2), but not 10.5 or '10'
        whole = isinstance(value, int) or (isinstance(value, float) and value.is_integer() and abs(value) < 2**53)
        if self.integer and not whole:
            ctx.add(path, raw, f"{show(value)} is not an integer; expected {self.describe()}")
            return MISSING
        too_small = self.minimum is not None and (
            number <= self.minimum if self.exclusive_minimum else number < self.minimum
        )
        too_large = self.maximum is not None and number > self.maximum
        if too_small or too_large:
            ctx.add(path, raw, f"{show(value)} is out of range; expected {self.describe()}")
            return MISSING
        return int(value) if self.integer else number


@dataclass
class Text(Spec):
    pattern: str = ""  # a human description of allowed names, when restricted

    def describe(self) -> str:
        return "a string" + (f" ({self.pattern})" if self.pattern else "")

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if not isinstance(value, str) or not value.strip():
            ctx.add(path, raw, f"{show(value)} is not a non-empty string; expected {self.describe()}")
            return MISSING
        return value


@dataclass
class Name(Text):
    """An identifier usable as a PDDL object name: letters, digits, '_' and '-'."""

    pattern: str = "letters, digits, '_' or '-', starting with a letter"

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            value = str(value)
        text = super().check(value, ctx, path, raw)
        if text is MISSING:
            return MISSING
        if not (text[0].isalpha() and all(c.isalnum() or c in "_-" for c in text)):
            ctx.add(path, raw, f"{show(text)} is not a valid name; expected {self.describe()}")
            return MISSING
        return text


@dataclass
class Flag(Spec):
    def describe(self) -> str:
        return "true or false"

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if not isinstance(value, bool):
            ctx.add(path, raw, f"{show(value)} is not a boolean; expected {self.describe()}")
            return MISSING
        return value


@dataclass
class Choice(Spec):
    choices: tuple[str, ...] = ()

    def describe(self) -> str:
        return "one of " + ", ".join(self.choices)

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if value not in self.choices:
            hint = _did_you_mean(str(value), self.choices)
            ctx.add(path, raw, f"{show(value)} is not allowed{hint}; expected {self.describe()}")
            return MISSING
        return value


@dataclass
class Vector(Spec):
    """A fixed-length list of quantities, one dimension per element (a point, a pose)."""

    dimensions: tuple[str | None, ...] = ()
    names: str = ""  # "x, y" for messages
    max_abs: float | None = None  # bound on the magnitude of the length elements (coordinates)

    def describe(self) -> str:
        units = ", ".join(si_unit(d) or "-" for d in self.dimensions)
        return f"a list of {len(self.dimensions)} numbers [{self.names}] in ({units})"

    def unit(self) -> str:
        return ", ".join(si_unit(d) or "-" for d in self.dimensions)

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if not isinstance(value, list) or len(value) != len(self.dimensions):
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        out = []
        for i, (item, dim) in enumerate(zip(value, self.dimensions, strict=True)):
            try:
                number = parse_quantity(item, dim)
            except UnitError as err:
                ctx.add(path, raw, f"element {i} {show(item)} {err}; expected {self.describe()}")
                return MISSING
            if not math.isfinite(number):
                ctx.add(path, raw, f"element {i} {show(item)} is not finite; expected {self.describe()}")
                return MISSING
            if self.max_abs is not None and dim == "length" and abs(number) > self.max_abs:
                ctx.add(
                    path,
                    raw,
                    f"element {i} {show(item)} is out of range; expected coordinates within +-{self.max_abs:g} m "
                    "(farther out is beyond any map on Earth)",
                )
                return MISSING
            out.append(number)
        return tuple(out)


@dataclass
class PointList(Spec):
    """A list of [x, y] points: a polygon (>= 3), a polyline (>= 2) or a segment (== 2)."""

    min_points: int = 3
    max_points: int | None = None
    what: str = "polygon"
    max_abs: float | None = None  # bound on the magnitude of the coordinates

    def describe(self) -> str:
        if self.max_points == self.min_points:
            count = f"exactly {self.min_points}"
        elif self.max_points is not None:
            count = f"{self.min_points} to {self.max_points}"
        else:
            count = f"at least {self.min_points}"
        return f"a {self.what}: a list of {count} points [x, y] in m"

    def unit(self) -> str:
        return "m"

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        too_few = not isinstance(value, list) or len(value) < self.min_points
        too_many = self.max_points is not None and isinstance(value, list) and len(value) > self.max_points
        if too_few or too_many:
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        point = Vector(dimensions=("length", "length"), names="x, y", max_abs=self.max_abs)
        out = []
        for i, item in enumerate(value):
            p = point.check(item, ctx, join(path, i), (*raw, i))
            if p is MISSING:
                return MISSING
            out.append(p)
        return tuple(out)


@dataclass
class Covariance(Spec):
    """A symmetric positive-definite n x n matrix (the pose covariance)."""

    n: int = 3
    units: str = "m², m², rad²"

    def describe(self) -> str:
        return f"a symmetric positive-definite {self.n}x{self.n} matrix ({self.units} on the diagonal)"

    def unit(self) -> str:
        return self.units

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        shape_ok = (
            isinstance(value, list)
            and len(value) == self.n
            and all(isinstance(row, list) and len(row) == self.n for row in value)
        )
        if not shape_ok or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for row in value for v in row
        ):
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        m = np.array([[as_float(v) for v in row] for row in value], dtype=float)
        if not np.all(np.isfinite(m)):
            ctx.add(path, raw, f"{show(value)} has NaN or infinite entries; expected {self.describe()}")
            return MISSING
        if not np.allclose(m, m.T, rtol=1e-9, atol=1e-12):
            ctx.add(path, raw, f"{show(value)} is not symmetric; expected {self.describe()}")
            return MISSING
        if np.linalg.eigvalsh(m).min() <= 0.0:
            ctx.add(path, raw, f"{show(value)} is not positive definite; expected {self.describe()}")
            return MISSING
        return tuple(tuple(float(v) for v in row) for row in value)


@dataclass
class NameList(Spec):
    """A list of names (the rooms of a goal)."""

    what: str = "room names"

    def describe(self) -> str:
        return f"a list of {self.what}"

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if not isinstance(value, list):
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        out = []
        for i, item in enumerate(value):
            name = Name().check(item, ctx, join(path, i), (*raw, i))
            if name is not MISSING:
                out.append(name)
        return tuple(out)


@dataclass
class NameMap(Spec):
    """A mapping from names (robots) to a value spec (their target rooms)."""

    value: Spec = field(default_factory=NameList)

    def describe(self) -> str:
        return f"a mapping from robot names to {self.value.describe()}"

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if not isinstance(value, dict):
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        out = {}
        for key, item in value.items():
            if Name().check(key, ctx, join(path, key), (*raw, key)) is MISSING:
                continue
            checked = self.value.check(item, ctx, join(path, key), (*raw, key))
            if checked is not MISSING:
                out[str(key)] = checked
        return out


@dataclass
class ListOf(Spec):
    """A list whose items all follow one spec (the walls of a map)."""

    item: Spec = field(default_factory=Spec)
    what: str = "items"

    def describe(self) -> str:
        return f"a list of {self.what}, each {self.item.describe()}"

    def unit(self) -> str:
        return self.item.unit()

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if not isinstance(value, list):
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        out = []
        for i, item in enumerate(value):
            checked = self.item.check(item, ctx, join(path, i), (*raw, i))
            if checked is not MISSING:
                out.append(checked)
        return tuple(out)


@dataclass
class Field:
    spec: Spec
    doc: str
    required: bool = False
    default: Any = None  # in SI units; None with required=False means "absent is fine"


@dataclass
class Section(Spec):
    """A mapping with known keys; unknown keys are errors with a did-you-mean hint."""

    fields: dict[str, Field] = field(default_factory=dict)
    #: extra checks over the converted section: (section, ctx, path, raw) -> None
    post: Callable[[dict[str, Any], Ctx, str, tuple[Any, ...]], None] | None = None
    #: an absent (or null) optional section is None rather than its defaults: a part the
    #: scenario may leave out (a sensor the robots do not carry); ``{}`` gives the defaults
    absent_is_none: bool = False

    def describe(self) -> str:
        return "a mapping with keys " + ", ".join(self.fields)

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if value is None:
            value = {}
        if not isinstance(value, dict):
            ctx.add(path, raw, f"{show(value)} is not a mapping; expected {self.describe()}")
            return MISSING
        out: dict[str, Any] = {}
        for key in value:
            if key not in self.fields:
                hint = _did_you_mean(str(key), self.fields)
                ctx.add(join(path, key), (*raw, key), f"unknown key{hint}; expected one of {', '.join(self.fields)}")
        complete = True
        for key, fld in self.fields.items():
            sub = join(path, key)
            if key not in value or (value[key] is None and fld.required):
                if fld.required:
                    ctx.add(sub, (*raw, key), f"is missing; expected {fld.spec.describe()}")
                    complete = False
                    out[key] = MISSING
                elif isinstance(fld.spec, Section) and not fld.spec.absent_is_none:
                    out[key] = fld.spec.check({}, ctx, sub, (*raw, key))
                else:
                    out[key] = fld.default
                continue
            if value[key] is None:
                # an absent optional section still yields its defaults (unless absent means none)
                section = isinstance(fld.spec, Section) and not fld.spec.absent_is_none
                out[key] = fld.spec.check({}, ctx, sub, (*raw, key)) if section else fld.default
                continue
            checked = fld.spec.check(value[key], ctx, sub, (*raw, key))
            if checked is MISSING:
                complete = False
                if fld.required:
                    out[key] = MISSING
                elif isinstance(fld.spec, Section) and not fld.spec.absent_is_none:
                    # a bad optional section (`roadmap: 5`, reported above) falls back to its defaults
                    out[key] = fld.spec.check({}, Ctx(), sub, (*raw, key))
                else:
                    out[key] = fld.default
            else:
                out[key] = checked
        if complete and self.post is not None:
            self.post(out, ctx, path, raw)
        return out


@dataclass
class NamedList(Spec):
    """A list of sections that each have a unique ``name``; paths use the names."""

    item: Section = field(default_factory=Section)
    what: str = "item"
    min_items: int = 0

    def describe(self) -> str:
        return f"a list of {self.what}s, each a mapping with keys " + ", ".join(self.item.fields)

    def check(self, value: Any, ctx: Ctx, path: str, raw: tuple[Any, ...]) -> Any:
        if value is None:
            value = []
        if not isinstance(value, list):
            ctx.add(path, raw, f"{show(value)} is not {self.describe()}")
            return MISSING
        if len(value) < self.min_items:
            ctx.add(path, raw, f"has {len(value)} {self.what}s; expected at least {self.min_items}")
        out, seen = [], set()
        for i, item in enumerate(value):
            name = item.get("name") if isinstance(item, dict) else None
            usable = isinstance(name, str) and name and name not in seen
            sub = join(path, name) if usable else join(path, i)
            if isinstance(name, str) and name in seen:
                ctx.add(
                    join(path, i) + ".name",
                    (*raw, i, "name"),
                    f"duplicate {self.what} name {show(name)}; expected unique names",
                )
            checked = self.item.check(item, ctx, sub, (*raw, i))
            if isinstance(name, str):
                seen.add(name)
            if checked is not MISSING and not any(v is MISSING for v in checked.values()):
                out.append(checked)
        return out


def _did_you_mean(word: str, options: Any) -> str:
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def reference_rows(spec: Spec, path: str = "") -> Iterator[tuple[str, str, str, str, str]]:
    """Rows (key, type, unit, default, meaning) of the reference table, depth first."""
    if isinstance(spec, Section):
        for key, fld in spec.fields.items():
            sub = join(path, key)
            child = fld.spec
            if isinstance(child, (Section, NamedList)):
                kind = "list" if isinstance(child, NamedList) else "mapping"
                absent = "(none)" if isinstance(child, Section) and child.absent_is_none else ""
                yield sub, kind, "", "required" if fld.required else absent, fld.doc
                inner = child.item if isinstance(child, NamedList) else child
                yield from reference_rows(inner, sub + ("[]" if isinstance(child, NamedList) else ""))
            else:
                default = "required" if fld.required else _fmt_default(fld.default, child)
                yield sub, _kind(child), child.unit(), default, fld.doc


def _kind(spec: Spec) -> str:
    if isinstance(spec, Number):
        kind = "integer" if spec.integer else "number"
        return f"{kind} {spec.bounds()}".strip().replace("<=", "≤").replace(">=", "≥")
    return {
        Text: "string",
        Name: "name",
        Flag: "boolean",
        Choice: " \\| ".join(getattr(spec, "choices", ())),
        Vector: f"[{getattr(spec, 'names', '')}]",
        PointList: getattr(spec, "what", "points"),
        Covariance: "3x3 matrix",
        NameList: "list of names",
        NameMap: "mapping",
        ListOf: f"list of {getattr(spec, 'what', 'items')}",
    }.get(type(spec), type(spec).__name__)


def _fmt_default(default: Any, spec: Spec) -> str:
    if default is None:
        return "(none)"
    if isinstance(spec, Number) and spec.dimension == "angle":
        return f"{math.degrees(default):g} deg"
    if isinstance(default, bool):
        return str(default).lower()
    if isinstance(default, float):
        return f"{default:g}"
    if isinstance(default, tuple):
        return "[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in default) + "]"
    return str(default)
