"""The values of BT.CPP 4's script language and how they combine, as BT.CPP 4.8's ``Any`` does:
whole numbers (int64), doubles, strings; arithmetic in doubles, a string beside a number read as
one where BT.CPP reads it so, an error where BT.CPP refuses (:mod:`thymio_bt.btcpp.runtime.script`
parses the scripts that use them).

Example::

    >>> arith("+", 1, 2), arith("+", "3", "4"), concat("n=", 2.5), compare("==", "3abc", 3, {})
    (3.0, '34', 'n=2.500000', True)
    >>> arith("+", "3", 1)
    Traceback (most recent call last):
    ...
    thymio_bt.btcpp.runtime.values.ScriptError: '+' of the string '3' and 1 is not permitted
"""

from __future__ import annotations

import math
import re
from typing import Any

from thymio_bt.errors import ThymioBtError

#: numbers closer than this are equal (BT.CPP compares doubles within float's epsilon)
EPSILON = 1.1920928955078125e-07
INT64 = (-(2**63), 2**63 - 1)
#: a string's leading number, as C's ``strtod`` reads it
_LEADING_NUMBER = re.compile(r"\s*[-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan)", re.IGNORECASE)


class ScriptError(ValueError, ThymioBtError):
    """A script that does not parse, or that fails as it runs (a missing entry, a wrong type)."""


def truth(value: Any) -> bool:
    """A script's value as a condition (BT.CPP's ``cast<bool>``): 0 or 1, a double not below 0; a
    string is an error."""
    if isinstance(value, float):
        if value < 0:
            raise ScriptError(f"{text(value)} is not a condition (below 0)")
        return bool(value)
    if isinstance(value, int):
        if value not in (0, 1):
            raise ScriptError(f"{value} is not a condition (0 or 1)")
        return bool(value)
    raise ScriptError(f"{shown(value)} is not a condition")


def shown(value: Any) -> str:
    """A value in a message."""
    return f"the string '{value}'" if isinstance(value, str) else repr(value)


def is_number(value: Any) -> bool:
    """Whether BT.CPP would hold ``value`` as a number (a Python bool counts: it is 0 or 1)."""
    return isinstance(value, (int, float))


def double(value: Any) -> float:
    """A number as a double; a whole number a double cannot hold exactly is an error, as in BT.CPP."""
    if isinstance(value, float):
        return value
    if float(value) != value:
        raise ScriptError(f"{value} cannot be converted to a double exactly")
    return float(value)


def string_number(text: str, enums: dict[str, int]) -> float:
    """A string as a number: ``true``, ``false``, an enum's name, else its leading number (C's ``strtod``)."""
    if text in ("true", "false"):
        return float(text == "true")
    if text in enums:
        return float(enums[text])
    match = _LEADING_NUMBER.match(text)
    if match is None:
        raise ScriptError(f"the string '{text}' is not a number")
    return float(match.group().strip())


def text(value: Any) -> str:
    """A value in a string (BT.CPP's ``cast<std::string>``: a double as C's ``%f``)."""
    if isinstance(value, float):
        if math.isnan(value):
            return "-nan" if math.copysign(1.0, value) < 0 else "nan"
        return f"{value:f}"
    if isinstance(value, bool):
        return str(int(value))
    return str(value)


def _divide(a: float, b: float) -> float:
    """IEEE division, as C++ computes it (``inf`` or ``nan`` by zero)."""
    if b != 0:
        return a / b
    if a == 0 or math.isnan(a):
        return -math.nan  # x86's default NaN carries the sign bit: BT.CPP writes it -nan
    return math.copysign(math.inf, a) * math.copysign(1.0, b)


def arith(op: str, left: Any, right: Any) -> Any:
    """``+ - * /``: numbers give a double, two strings joined by ``+``; anything else is an error."""
    if is_number(left) and is_number(right):
        a, b = double(left), double(right)
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        return _divide(a, b)
    if op == "+" and isinstance(left, str) and isinstance(right, str):
        return left + right
    raise ScriptError(f"'{op}' of {shown(left)} and {shown(right)} is not permitted")


def _whole(value: Any) -> int:
    """A number as an int64 for a bitwise operator (a fraction or a double out of range is an error)."""
    if isinstance(value, float) and (not value.is_integer() or not INT64[0] <= value <= INT64[1]):
        raise ScriptError(f"bitwise operators want whole numbers, not {text(value)}")
    return int(value)


def bits(op: str, left: Any, right: Any) -> float:
    """``& | ^`` on whole numbers, as a double."""
    if not (is_number(left) and is_number(right)):
        raise ScriptError(f"'{op}' of {shown(left)} and {shown(right)} is not permitted")
    a, b = _whole(left), _whole(right)
    return float(a & b if op == "&" else a | b if op == "|" else a ^ b)


def logic(op: str, left: Any, right: Any) -> float:
    """``&& ||`` on two numbers, both already computed, as 1.0 or 0.0."""
    if not (is_number(left) and is_number(right)):
        raise ScriptError(f"'{op}' of {shown(left)} and {shown(right)} is not permitted")
    a, b = truth(left), truth(right)
    return float(a and b if op == "&&" else a or b)


def concat(left: Any, right: Any) -> str:
    """``..``: at least one side a string."""
    if not (isinstance(left, str) or isinstance(right, str)) or not all(
        isinstance(v, str) or is_number(v) for v in (left, right)
    ):
        raise ScriptError(f"'..' of {shown(left)} and {shown(right)} is not permitted")
    return text(left) + text(right)


def unary(op: str, value: Any) -> float:
    """Prefix ``-``, ``~`` and ``!`` on a number, as a double."""
    if not is_number(value):
        raise ScriptError(f"'{op}' of {shown(value)} is not permitted")
    v = double(value)
    if op == "-":
        return -v
    if op == "!":
        return float(not v)
    if not (math.isfinite(v) and INT64[0] <= v <= INT64[1]):
        raise ScriptError(f"'~' of {text(v)}: out of range")
    return float(~int(v))


def compare(op: str, left: Any, right: Any, enums: dict[str, int]) -> bool:
    """One comparison: numbers (a string beside a number read as one) or two strings."""
    if isinstance(left, str) and isinstance(right, str):
        a: Any = left
        b: Any = right
    elif is_number(left) and is_number(right):
        a, b = double(left), double(right)
    elif isinstance(left, str) and is_number(right):
        a, b = string_number(left, enums), double(right)
    elif is_number(left) and isinstance(right, str):
        a, b = double(left), string_number(right, enums)
    else:
        raise ScriptError(f"cannot compare {shown(left)} and {shown(right)}")
    if op in ("==", "!="):
        same = abs(a - b) <= EPSILON if isinstance(a, float) else a == b
        return same if op == "==" else not same
    # written as BT.CPP writes them, negated: a comparison with nan holds
    return not {"<": a >= b, "<=": a > b, ">": a <= b, ">=": a < b}[op]


def ternary_truth(value: Any) -> bool:
    """The condition of ``c ? a : b``: a number not 0, or a string of one."""
    if isinstance(value, str):
        match = _LEADING_NUMBER.match(value)
        if match is None:
            raise ScriptError(f"the string '{value}' is not a condition")
        return float(match.group().strip()) != 0
    if not is_number(value):
        raise ScriptError(f"{shown(value)} is not a condition")
    return value != 0


def converted(name: str, old: Any, new: Any) -> Any:
    """``new`` written into the entry that holds ``old``, as BT.CPP's ``copyInto`` converts it."""
    if isinstance(old, bool) or isinstance(new, bool):
        if is_number(new) and new in (0, 1):
            return bool(new) if isinstance(old, bool) else int(new)
    elif isinstance(old, int) and is_number(new):
        if isinstance(new, float) and not (new.is_integer() and INT64[0] <= new <= INT64[1]):
            raise ScriptError(f"'{name}' holds a whole number: cannot write {text(new)} into it")
        return int(new)
    elif isinstance(old, float) and is_number(new):
        return double(new)
    elif type(old) is type(new):
        return new
    raise ScriptError(f"cannot write {shown(new)} into '{name}', which holds {shown(old)}")
