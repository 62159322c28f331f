"""A small, safe parser for values with units: ``pi/2``, ``90deg``, ``-45 deg``, ``5cm``, ``0.1 m/s``.

Values are converted to SI (metres, radians, seconds). The grammar is arithmetic on numbers,
``pi`` and ``$parameter`` references, with ``+ - * /`` and parentheses, optionally followed by one
unit. Nothing is ever passed to ``eval``.

Example::

    >>> parse_value("pi/2").value
    1.5707963267948966
    >>> parse_value("5cm").value, parse_value("5cm").kind
    (0.05, 'length')
    >>> round(parse_value("-45 deg").value, 4)
    -0.7854
    >>> parse_pose("50cm, 30cm, 90deg")
    (0.5, 0.3, 1.5707963267948966)
    >>> try:
    ...     parse_value("2cm*3cm")
    ... except UnitError as exc:
    ...     print(exc)
    ...     print(exc.hint)
    cannot multiply or divide two values with units in '2cm*3cm'
    a unit binds to the number before it: write 2*$side - 10cm, not 2cm*3cm
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from thymio_bt.errors import ThymioBtError, did_you_mean

#: unit -> (factor to SI, kind)
UNITS: dict[str, tuple[float, str]] = {
    "m": (1.0, "length"),
    "cm": (0.01, "length"),
    "mm": (0.001, "length"),
    "rad": (1.0, "angle"),
    "deg": (math.pi / 180.0, "angle"),
    "°": (math.pi / 180.0, "angle"),
    "s": (1.0, "time"),
    "ms": (0.001, "time"),
    "min": (60.0, "time"),
    "m/s": (1.0, "speed"),
    "cm/s": (0.01, "speed"),
    "mm/s": (0.001, "speed"),
    "rad/s": (1.0, "angular_speed"),
    "deg/s": (math.pi / 180.0, "angular_speed"),
    "hz": (1.0, "frequency"),
    "Hz": (1.0, "frequency"),
    "KiB": (1 / 1024, "memory"),
    "MiB": (1.0, "memory"),
    "GiB": (1024.0, "memory"),
    "kB": (1e3 / 2**20, "memory"),
    "MB": (1e6 / 2**20, "memory"),
    "GB": (1e9 / 2**20, "memory"),
}

#: The SI unit printed for each kind.
SI_UNIT = {"length": "m", "angle": "rad", "time": "s", "speed": "m/s", "angular_speed": "rad/s", "frequency": "Hz"}
SI_UNIT["memory"] = "MiB"  # not SI: what limits are given in

_TOKEN = re.compile(
    r"\s*(?:(?P<num>\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<ref>\$[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<unit>(?:cm|mm|m|rad|deg)/(?!pi\b)[A-Za-z]+|[A-Za-z_°][A-Za-z0-9_]*)"  # cm/sec: one unit, misspelt
    r"|(?P<op>[-+*/()]))"
)


#: How a value of each kind is written, for hints.
EXAMPLES = {
    "length": "5cm, 0.05 m or 50mm",
    "angle": "90deg, pi/2 or 1.57 rad",
    "time": "2 s, 500ms or 1 min",
    "speed": "10cm/s or 0.1 m/s",
    "angular_speed": "90deg/s or 1.5 rad/s",
    "frequency": "10 Hz",
    "memory": "512MiB or 2GiB",
}

#: A proximity threshold as a real Thymio's reading ("3400 raw"), converted to the distance at which
#: the calibration table gives that reading. Not a factor: it stands alone, never in arithmetic.
_RAW = re.compile(r"\s*(\d+(?:\.\d*)?)\s*raw\s*")

#: Deepest nesting of parentheses accepted (a guard against pathological input, not a style rule).
MAX_NESTING = 50

#: the largest angle written without a unit (rad) taken as it is: one turn, TurnAngle's own bound
FULL_TURN = 2 * math.pi


class UnitError(ValueError, ThymioBtError):
    """A value that does not parse; the message says what was expected, ``hint`` how to fix it."""

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.hint = hint


@dataclass(frozen=True, slots=True)
class Quantity:
    """A parsed number in SI units, with the kind of its unit (None when it had no unit)."""

    value: float
    kind: str | None = None


def _tokens(text: str) -> list[tuple[str, str]]:
    """The tokens of ``text``: (group name, text) pairs; an unexpected character is a :class:`UnitError`."""
    pos, out = 0, []
    text = text.strip()
    while pos < len(text):
        match = _TOKEN.match(text, pos)
        if not match or match.end() == pos:
            raise UnitError(f"unexpected '{text[pos:].strip()[:10]}' in '{text}'")
        kind = match.lastgroup or ""
        out.append((kind, match.group(kind)))
        pos = match.end()
    return out


class _Parser:
    """Recursive descent over tokens; every value carries its unit kind (None for plain numbers).

    A unit binds to the number or parenthesis right before it (``2*$side - 10cm`` is
    2·side − 0.1 m); adding quantities of different kinds, or multiplying two, is an error.
    """

    def __init__(self, text: str, resolve: Callable[[str], Quantity] | None, kind: str | None = None) -> None:
        self.text = text
        self.toks = _tokens(text)
        self.i = 0
        self.depth = 0
        self.resolve = resolve
        self.kind = kind

    def peek(self) -> tuple[str, str] | None:
        """The next token, None at the end."""
        return self.toks[self.i] if self.i < len(self.toks) else None

    def take(self) -> tuple[str, str]:
        """The next token, consumed; the end of the text is a :class:`UnitError`."""
        tok = self.peek()
        if tok is None:
            raise UnitError(f"'{self.text}' ends too early")
        self.i += 1
        return tok

    def parse(self) -> Quantity:
        """The whole text as one quantity (anything left over is an error)."""
        value, kind = self.expr()
        if self.peek() is not None:
            raise UnitError(f"unexpected '{self.peek()[1]}' in '{self.text}'")  # type: ignore[index]
        return Quantity(value, kind)

    def _combine(self, a: str | None, b: str | None, op: str) -> str | None:
        """The kind of ``a op b``: adding needs the same kind (or none), multiplying at most one."""
        if a and b and (op in "*/" or a != b):
            what = "multiply or divide two values with units" if op in "*/" else f"add {_named(a)} and {_named(b)}"
            raise UnitError(
                f"cannot {what} in '{self.text}'",
                "a unit binds to the number before it: write 2*$side - 10cm, not 2cm*3cm"
                if op in "*/"
                else "both sides of + and - need the same kind of unit",
            )
        return a or b

    def expr(self) -> tuple[float, str | None]:
        """expr := term (("+" | "-") term)*"""
        value, kind = self.term()
        while (tok := self.peek()) and tok[0] == "op" and tok[1] in "+-":
            self.i += 1
            rhs, rkind = self.term()
            kind = self._combine(kind, rkind, tok[1])
            value = value + rhs if tok[1] == "+" else value - rhs
        return value, kind

    def term(self) -> tuple[float, str | None]:
        """term := unary (("*" | "/") unary)*"""
        value, kind = self.unary()
        while (tok := self.peek()) and tok[0] == "op" and tok[1] in "*/":
            self.i += 1
            rhs, rkind = self.unary()
            kind = self._combine(kind, rkind, tok[1])
            if tok[1] == "/":
                if rhs == 0:
                    raise UnitError(f"division by zero in '{self.text}'")
                value /= rhs
            else:
                value *= rhs
        return value, kind

    def unary(self) -> tuple[float, str | None]:
        """unary := ("+" | "-")* atom unit?"""
        sign = 1.0
        while (tok := self.peek()) and tok[0] == "op" and tok[1] in "+-":  # a loop: '-----5' nests nothing
            self.i += 1
            sign = -sign if tok[1] == "-" else sign
        value, kind = self.unit(*self.atom())
        return sign * value, kind

    def unit(self, value: float, kind: str | None) -> tuple[float, str | None]:
        """The unit after a value, if any, applied to it (a value already with a unit takes none)."""
        tok = self.peek()
        if not tok or tok[0] != "unit" or tok[1] == "pi":
            return value, kind
        self.i += 1
        if tok[1] == "raw":
            raise UnitError(
                f"a raw reading cannot take part in arithmetic in '{self.text}'",
                "raw readings are not proportional to distance: write one reading alone, e.g. 3400 raw",
            )
        if tok[1] not in UNITS:
            raise UnitError(f"unknown unit '{tok[1]}' in '{self.text}'", unit_hint(tok[1], self.kind))
        if kind is not None:
            raise UnitError(f"'{tok[1]}' follows a value that already has a unit in '{self.text}'")
        factor, unit_kind = UNITS[tok[1]]
        return value * factor, unit_kind

    def atom(self) -> tuple[float, str | None]:
        """atom := number | "(" expr ")" | "pi" | $name"""
        kind, text = self.take()
        if kind == "num":
            return float(text), None
        if kind == "op" and text == "(":
            self.depth += 1
            if self.depth > MAX_NESTING:
                raise UnitError(f"more than {MAX_NESTING} nested parentheses in '{self.text[:40]}...'")
            value = self.expr()
            if self.peek() != ("op", ")"):
                raise UnitError(f"missing ')' in '{self.text}'")
            self.i += 1
            self.depth -= 1
            return value
        if kind == "unit" and text == "pi":
            return math.pi, None
        if kind == "ref":
            if self.resolve is None:
                raise UnitError(f"'{text}' refers to a parameter, but none are defined here")
            try:
                quantity = self.resolve(text[1:])
            except KeyError:
                raise UnitError(f"unknown parameter '{text}' in '{self.text}'") from None
            return quantity.value, quantity.kind
        raise UnitError(f"expected a number in '{self.text}', found '{text}'")


def parse_value(
    text: str | int | float, resolve: Callable[[str], Quantity] | None = None, kind: str | None = None
) -> Quantity:
    """Parse a number with an optional unit into SI; raise :class:`UnitError` (a ``ValueError``).

    ``resolve`` gives the value of a ``$name``; it may raise ``KeyError`` or :class:`UnitError`.
    ``kind``, the kind the value is wanted in, only makes the hints of a misspelt unit its own.
    """
    if isinstance(text, bool):
        raise UnitError(f"expected a number, found {text!r}")
    if isinstance(text, (int, float)):
        if not math.isfinite(text):
            raise UnitError(f"{text!r} is not a finite number")
        return Quantity(float(text))
    raw = _RAW.fullmatch(str(text))
    if raw:
        return _raw_reading(float(raw.group(1)))
    quantity = _Parser(str(text), resolve, kind).parse()
    if not math.isfinite(quantity.value):
        raise UnitError(f"'{text}' is not a finite number")
    return quantity


def _raw_reading(reading: float) -> Quantity:
    """The distance at which a real Thymio's sensor gives ``reading`` (Webots' Thymio II table)."""
    from thymio_bt.sensor_tables import WEBOTS_THYMIO2 as table

    if not 0 < reading <= table.max_reading:
        raise UnitError(
            f"a raw reading must be between 1 and {table.max_reading:g}, got {reading:g}",
            "0 means nothing in range; 4308 is as close as the table goes (e.g. 3400 raw is 3.2 cm)",
        )
    return Quantity(table.to_metres(reading), "length")


def parse_pose(text: str, resolve: Callable[[str], Quantity] | None = None) -> tuple[float, float, float]:
    """Parse ``X,Y,YAW`` (e.g. ``0.5,0.3,pi/2`` or ``50cm, 30cm, 90deg``) into metres and radians."""
    parts = [p for p in str(text).split(",")]
    if len(parts) != 3:
        raise UnitError(
            f"expected X,Y,YAW (three comma-separated values), got '{text}'",
            "e.g. 0.5,0.3,pi/2 (metres and radians) or 50cm,30cm,90deg; or the name of a spawn of the maze",
        )
    x, y, yaw = (parse_value(p, resolve, kind) for p, kind in zip(parts, ("length", "length", "angle"), strict=True))
    for name, q, kind in (("X", x, "length"), ("Y", y, "length"), ("YAW", yaw, "angle")):
        error = check_kind(q, kind)
        if error:
            raise UnitError(f"{name} of '{text}': {error}", error.hint)
    return x.value, y.value, yaw.value


def parse_kind(text: str | int | float, resolve: Callable[[str], Quantity] | None, kind: str | None) -> float:
    """A value for a number of ``kind``, in its SI unit: :func:`parse_value`, then :func:`check_kind`
    (how the mission loader and the unit types read every number).

    >>> parse_kind("20cm", None, "length")
    0.2
    >>> parse_kind("2s", None, "length")
    Traceback (most recent call last):
    ...
    thymio_bt.inputs.units.UnitError: expected a length (in m), got a time
    """
    quantity = parse_value(text, resolve, kind)
    error = check_kind(quantity, kind)
    if error:
        raise error
    return quantity.value


def check_kind(quantity: Quantity, expected: str | None) -> UnitError | None:
    """The problem (message and hint) when a value does not fit a parameter of kind ``expected``,
    else None: a unit of another kind, or an angle written without a unit past a full turn.

    A bare number is in the parameter's SI unit, radians for an angle; one past a full turn was
    surely meant in degrees (a yaw of 90 would be 116.6 degrees), wherever an angle is read: a
    node's parameter, every pose's yaw, a maze's spawn, an assignment's start.

    >>> print(check_kind(Quantity(90.0), "angle"))
    90 rad is more than a full turn (an angle without a unit is in radians)
    >>> check_kind(Quantity(90.0), "angle").hint
    'did you mean 90deg? a bare number is in rad; write an angle: 90deg, pi/2 or 1.57 rad'
    >>> check_kind(Quantity(math.pi / 2), "angle") is None and check_kind(Quantity(7.0, "angle"), "angle") is None
    True
    """
    if expected is None or quantity.kind == expected:
        return None
    if quantity.kind is None:
        if expected == "angle" and abs(quantity.value) > FULL_TURN:
            meant = quantity.value.is_integer() and abs(quantity.value) <= 360  # 90, not 4*pi
            guess = f"did you mean {quantity.value:g}deg? " if meant else ""
            return UnitError(
                f"{quantity.value:g} rad is more than a full turn (an angle without a unit is in radians)",
                f"{guess}a bare number is in rad; {kind_hint(expected)}",
            )
        return None
    return UnitError(
        f"expected {_named(expected)} (in {SI_UNIT.get(expected, '?')}), got {_named(quantity.kind)}",
        kind_hint(expected),
    )


#: units written out as words, singular: what a unit of that name is written here
_WORDS = {
    "degree": "deg",
    "radian": "rad",
    "metre": "m",
    "meter": "m",
    "centimetre": "cm",
    "centimeter": "cm",
    "millimetre": "mm",
    "millimeter": "mm",
    "second": "s",
    "sec": "s",
    "millisecond": "ms",
    "minute": "min",
}


def unit_hint(unknown: str, kind: str | None = None) -> str:
    """The hint for an unknown unit: the unit of the value's own ``kind`` it is closest to (or that
    its word names) first, then any unit.

    >>> unit_hint("degrees", "angle"), unit_hint("degrees")
    ("did you mean 'deg'? write an angle: 90deg, pi/2 or 1.57 rad", "did you mean 'deg'?")
    >>> unit_hint("seconds", "angle")
    "'seconds' is a time: write an angle: 90deg, pi/2 or 1.57 rad"
    >>> unit_hint("cm/sec", "speed"), unit_hint("metres", "length")
    ("did you mean 'cm/s'? write a speed: 10cm/s or 0.1 m/s", "did you mean 'm'? write a length: 5cm, 0.05 m or 50mm")
    """
    word = _WORDS.get(unknown.lower().removesuffix("s")) or _WORDS.get(unknown.lower())
    own = [u for u, (_, k) in UNITS.items() if k == kind]
    if word is not None and kind is not None and UNITS[word][1] != kind:
        return f"'{unknown}' is {_named(UNITS[word][1])}: {kind_hint(kind)}"
    close = [word] if word else difflib.get_close_matches(unknown, own, n=1, cutoff=0.5)
    if close:
        return f"did you mean '{close[0]}'?" + (f" {kind_hint(kind)}" if kind in EXAMPLES else "")
    # memory sizes are units of an assignment's limits only: not offered for a robot's quantities
    listed = did_you_mean(
        unknown, [u for u, (_, k) in UNITS.items() if u != "hz" and (k != "memory") == (kind != "memory")]
    )
    return f"{listed}; {kind_hint(kind)}" if kind in EXAMPLES else listed


def kind_hint(kind: str | None) -> str:
    """How a value of ``kind`` is written, e.g. 'write a length: 5cm, 0.05 m or 50mm'."""
    if kind is None or kind not in EXAMPLES:
        return ""
    return f"write {_named(kind)}: {EXAMPLES[kind]}"


def _named(kind: str) -> str:
    """'a length', 'an angle', 'an angular speed'."""
    words = kind.replace("_", " ")
    return ("an " if words[0] in "aeiou" else "a ") + words


ParamResolver = Callable[[str], Quantity]


def resolver_from(values: Mapping[str, Any]) -> ParamResolver:
    """A resolver for ``$name`` references from a mapping of parsed values (a parameter that is no
    number, such as ``bb:key`` or ``true``, is refused where it is used in a number).

    >>> resolve = resolver_from({"cell": Quantity(0.3, "length"), "turn": "bb:turn"})
    >>> parse_value("0.75 * $cell", resolve)
    Quantity(value=0.22499999999999998, kind='length')
    >>> parse_value("$turn", resolve)
    Traceback (most recent call last):
    ...
    thymio_bt.inputs.units.UnitError: parameter '$turn' is 'bb:turn', not a number
    """

    def resolve(name: str) -> Quantity:
        if name not in values:
            raise KeyError(name)
        value = values[name]
        if isinstance(value, Quantity):
            return value
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return Quantity(float(value))
        raise UnitError(f"parameter '${name}' is {value!r}, not a number")

    return resolve
