"""BT.CPP 4's script language (``Script``, ``ScriptCondition``, ``Precondition``, ``_skipIf``...),
parsed into Python closures by a small recursive-descent parser: nothing is ever ``eval``-ed.

It follows BT.CPP 4.8 (the version behaviortreepy bundles) as it behaves, checked against it by
``tests/test_btcpp_script.py``, quirks included:

- values are whole numbers (``3``, ``0x10``, ``true`` is 1), doubles (``2.5``, ``1e3``), strings
  (``'text'`` or ``"text"``) and blackboard entries by name; an enum stands for its number;
- arithmetic (``+ - * /``) gives a double; ``/`` by zero gives ``inf`` or ``nan``; ``+`` of two
  strings joins them; any other mix of a string and a number is an error, as is ``..`` (string
  concatenation) of two numbers; a double in a string reads as C's ``%f`` (``2.500000``);
- ``a - b + c`` is ``a - (b + c)``: BT.CPP evaluates ``+ -`` and ``* /`` right to left;
- one expression uses one family of operators, arithmetic (``+ - * /``, prefix ``-``), bitwise
  (``& | ^``, prefix ``~ !``) or concatenation (``..``): mixing them needs parentheses;
- comparisons chain (``a < b < c``), compare a string with a number as a number and numbers
  within 1.2e-7 as equal; ``&&`` and ``||`` evaluate both sides, left to right at one level, and
  want 0 or 1 (or a double); comparisons and logic give 1.0 or 0.0;
- ``c ? a : b`` does not chain without parentheses, nor does an assignment; ``:=`` creates an
  entry, ``=`` writes an existing one converted to its type (a whole-number entry refuses a
  fraction), ``+= -= *= /=`` compute in doubles (``+=`` of a string joins).

Statements are separated by ``;``; a script's value is its last statement's.

Example::

    >>> board = {}
    >>> run = parse("count := 3; count += 2; msg := 'n=' .. count; count > 4 && msg != ''")
    >>> run(board), board
    (1.0, {'count': 5, 'msg': 'n=5'})
    >>> parse("half := 5 / 2; 'h=' .. half")(board)           # a double, as BT.CPP writes it
    'h=2.500000'
    >>> parse("x := 10 - 4 - 3")(board)                       # 10 - (4 - 3), as BT.CPP computes it
    9.0
    >>> try:
    ...     parse("x := 1 + 2 & 3")
    ... except ScriptError as exc:
    ...     print(exc)
    '&' after '+': arithmetic, bitwise and '..' do not mix without parentheses
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, MutableMapping
from typing import Any

from thymio_bt.btcpp.runtime.values import (
    INT64,
    ScriptError,
    arith,
    bits,
    compare,
    concat,
    converted,
    is_number,
    logic,
    shown,
    string_number,
    ternary_truth,
    text,
    unary,
)

Board = MutableMapping[str, Any]
Script = Callable[[Board], Any]

_TOKEN = re.compile(
    r"\s*(?:(?P<num>0[xX][0-9a-fA-F]+|\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"
    r"|(?P<str>'[^']*'|\"[^\"]*\")"
    r"|(?P<name>[A-Za-z_@][A-Za-z0-9_]*)"
    r"|(?P<op>:=|\+=|-=|\*=|/=|==|!=|<=|>=|&&|\|\||\.\.|[-+*/<>!?:;()=&|^~]))"
)
_ASSIGN = (":=", "=", "+=", "-=", "*=", "/=")
_COMPARE = ("==", "!=", "<", "<=", ">", ">=")
#: the operator families an expression may not mix (BT.CPP's grammar: ``dsl::groups``)
_FAMILY = {"+": "arithmetic", "-": "arithmetic", "*": "arithmetic", "/": "arithmetic"}
_FAMILY.update({"&": "bitwise", "|": "bitwise", "^": "bitwise", "~": "bitwise", "!": "bitwise", "..": "concatenation"})


def tokenize(text: str) -> list[tuple[str, Any]]:
    """The script's tokens: (kind, value) with kind ``num``, ``str``, ``name`` or ``op``."""
    tokens: list[tuple[str, Any]] = []
    position = 0
    end = len(text.rstrip())
    while position < end:
        match = _TOKEN.match(text, position, end)
        if match is None or match.end() == position:
            raise ScriptError(f"unexpected character {text[position:].lstrip()[:1]!r} at column {position + 1}")
        kind = match.lastgroup or ""
        value: Any = match.group(kind)
        if kind == "num":
            value = _literal(value, text[match.end() : match.end() + 1])
        elif kind == "str":
            value = value[1:-1]
        elif kind == "name" and re.match(r"(?:true|false)\w", value):
            raise ScriptError(f"'{value}': a name may not start with true or false")
        tokens.append((kind, value))
        position = match.end()
    return tokens


def _literal(text: str, after: str) -> int | float:
    """A number literal: a whole number (int64) or a double; a letter or ``.`` right after it is an error."""
    if after == "." or after.isalpha() or after == "_":
        raise ScriptError(f"invalid suffix on the number {text}{after}")
    if text[:2] in ("0x", "0X"):
        value: int | float = int(text, 16)
    elif "." in text or "e" in text.lower():
        value = float(text)
        if math.isinf(value):
            raise ScriptError(f"the number {text} is out of range")
        return value
    else:
        value = int(text)
    if not INT64[0] <= value <= INT64[1]:
        raise ScriptError(f"the number {text} is out of range")
    return value


def parse(text: str, enums: dict[str, int] | None = None) -> Script:
    """The script as a function of the blackboard (a mapping) that returns the script's value."""
    if text and not text.strip():
        raise ScriptError("a script of blanks only (BT.CPP accepts an empty one)")
    parser = _Parser(tokenize(text), enums or {})
    if parser.at_end():
        return lambda board: None
    statements = [parser.statement()]
    while parser.accept(";"):
        statements.append(parser.statement())
    if not parser.at_end():
        raise ScriptError(f"unexpected {parser.peek()[1]!r}")

    def run(board: Board) -> Any:
        value = None
        for statement in statements:
            value = statement(board)
        return value

    return run


class _Parser:
    """Recursive descent over the tokens; each method returns a closure of the board. ``family``
    is the operator family the expression being read uses (parentheses start a new one)."""

    def __init__(self, tokens: list[tuple[str, Any]], enums: dict[str, int]) -> None:
        self.tokens, self.enums, self.index = tokens, enums, 0
        self.family: tuple[str, str] | None = None

    def peek(self) -> tuple[str, Any]:
        return self.tokens[self.index] if self.index < len(self.tokens) else ("end", None)

    def at_end(self) -> bool:
        return self.index >= len(self.tokens)

    def accept(self, *ops: str) -> str | None:
        kind, value = self.peek()
        if kind == "op" and value in ops:
            self.index += 1
            self._joins(str(value))
            return str(value)
        return None

    def _joins(self, op: str) -> None:
        """Note that the expression uses ``op``; one of another family is an error."""
        family = _FAMILY.get(op)
        if family is None:
            return
        if self.family is not None and self.family[0] != family:
            raise ScriptError(
                f"'{op}' after '{self.family[1]}': arithmetic, bitwise and '..' do not mix without parentheses"
            )
        self.family = self.family or (family, op)

    def expect(self, op: str) -> None:
        if not self.accept(op):
            found = self.peek()[1]
            raise ScriptError(f"expected '{op}'" + (f", found {found!r}" if found is not None else " at the end"))

    def nested(self) -> Script:
        """A whole expression with operator families of its own (in parentheses, a ternary's middle)."""
        outer, self.family = self.family, None
        inner = self.assignment()
        self.family = outer
        return inner

    def statement(self) -> Script:
        self.family = None
        return self.assignment()

    def assignment(self) -> Script:
        kind, name = self.peek()
        if kind == "name" and self.index + 1 < len(self.tokens):
            op = self.tokens[self.index + 1]
            if op[0] == "op" and op[1] in _ASSIGN:
                if name in self.enums or name in ("true", "false"):
                    raise ScriptError(f"cannot assign to '{name}'")
                self.index += 2
                value = self.ternary()
                if self.peek()[0] == "op" and self.peek()[1] in _ASSIGN:
                    raise ScriptError("an assignment's value cannot be an assignment (add parentheses)")
                return _assign(str(name), str(op[1]), value, self.enums)
        return self.ternary()

    def ternary(self) -> Script:
        condition = self.logical()
        if not self.accept("?"):
            return condition
        then = self.nested()
        self.expect(":")
        other = self.logical()
        if self.peek() == ("op", "?"):
            raise ScriptError("'?' after 'c ? a : b' needs parentheses")
        return lambda b: then(b) if ternary_truth(condition(b)) else other(b)

    def logical(self) -> Script:
        return self.left_to_right(("&&", "||"), self.comparison, logic)

    def comparison(self) -> Script:
        """``a < b <= c``: each pair compared in turn, stopping at the first that fails."""
        operands, ops = [self.bitwise_or()], []
        while (op := self.accept(*_COMPARE)) is not None:
            ops.append(op)
            operands.append(self.bitwise_or())
        if not ops:
            return operands[0]
        enums = self.enums

        def chain(b: Board) -> float:
            left = operands[0](b)
            for op, operand in zip(ops, operands[1:], strict=True):
                right = operand(b)
                if not compare(op, left, right, enums):
                    return 0.0
                left = right
            return 1.0

        return chain

    def bitwise_or(self) -> Script:
        return self.left_to_right(("|", "^"), self.bitwise_and, bits)

    def bitwise_and(self) -> Script:
        return self.left_to_right(("&",), self.concatenation, bits)

    def concatenation(self) -> Script:
        return self.left_to_right(("..",), self.sum, lambda op, left, right: concat(left, right))

    def left_to_right(self, ops: tuple[str, ...], operand: Callable[[], Script], apply: Callable[..., Any]) -> Script:
        """``operand`` (op ``operand``)*, the operators ``ops`` grouped from the left, each
        evaluated as ``apply(op, left, right)``."""
        left = operand()
        while (op := self.accept(*ops)) is not None:
            right = operand()
            left = (lambda lf, rt, o: lambda b: apply(o, lf(b), rt(b)))(left, right, op)
        return left

    def sum(self) -> Script:
        """``+ -``, evaluated right to left as BT.CPP does: ``a - b + c`` is ``a - (b + c)``."""
        return self.right_to_left(("+", "-"), self.product)

    def product(self) -> Script:
        """``* /``, right to left too."""
        return self.right_to_left(("*", "/"), self.unary)

    def right_to_left(self, ops: tuple[str, ...], operand: Callable[[], Script]) -> Script:
        """``operand`` (op ``operand``)*, the operators ``ops`` grouped from the right."""
        left = operand()
        op = self.accept(*ops)
        if op is None:
            return left
        right = self.right_to_left(ops, operand)
        return lambda b: arith(op, left(b), right(b))

    def unary(self) -> Script:
        op = self.accept("!", "-", "~")
        if op is None:
            return self.primary()
        inner = self.unary()
        return lambda b: unary(op, inner(b))

    def primary(self) -> Script:
        kind, value = self.peek()
        if kind == "end":
            raise ScriptError("expected a value at the end of the script")
        self.index += 1
        if kind in ("num", "str"):
            return lambda b: value
        if kind == "name":
            if value in ("true", "false"):
                flag = int(value == "true")
                return lambda b: flag
            if value in self.enums:
                number = float(self.enums[value])
                return lambda b: number
            return _read(str(value))
        if value == "(":
            inner = self.nested()
            self.expect(")")
            return inner
        if value == "+" and self.peek()[0] == "num":  # a literal's sign
            number = self.peek()[1]
            self.index += 1
            return lambda b: number
        raise ScriptError(f"expected a value, found {value!r}")


def _read(name: str) -> Script:
    """A blackboard entry's value (an error when there is none)."""

    def read(board: Board) -> Any:
        if name not in board:
            raise ScriptError(f"the blackboard has no entry '{name}'")
        return board[name]

    return read


def _assign(name: str, op: str, value: Script, enums: dict[str, int]) -> Script:
    """An assignment's closure: its value is the entry's new value."""

    def assign(board: Board) -> Any:
        if name not in board:
            if op != ":=":
                raise ScriptError(f"'{name}' is not on the blackboard: create it with '{name} := ...'")
            board[name] = None  # BT.CPP creates the entry, empty, before it computes the value
        new = value(board)
        if new is None:
            raise ScriptError(f"the value written to '{name}' is not set")
        old = board.get(name)
        if old is None:
            if op not in (":=", "="):
                raise ScriptError(f"'{name}' has no value for '{op}'")
        elif op in (":=", "="):
            if isinstance(new, str) and not isinstance(old, str) and is_number(old):
                new = string_number(new, enums)  # BT.CPP stores the number as a double
            else:
                new = converted(name, old, new)
        elif is_number(new):
            if not is_number(old):
                raise ScriptError(f"'{op}' needs a number in '{name}', which holds {shown(old)}")
            new = converted(name, old, arith(op[0], old, new))
        elif isinstance(new, str) and op == "+=":
            new = converted(name, old, text(old) + new)
        else:
            raise ScriptError(f"'{op}' of {shown(new)} is not permitted")
        board[name] = new
        return new

    return assign
