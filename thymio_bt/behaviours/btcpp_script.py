"""BT.CPP 4's script language (``Script``, ``ScriptCondition``, ``Precondition``, ``_skipIf``...),
parsed into Python closures by a small recursive-descent parser: nothing is ever ``eval``-ed.

Values are numbers, strings (``'text'``), booleans (``true``/``false``) and blackboard entries by
name; an enum (a name given in ``enums``) stands for its number. Operators, loosest first:
assignment (``:=`` creates an entry, ``=`` writes an existing one, ``+= -= *= /=``), the ternary
``c ? a : b``, ``||``, ``&&``, comparisons (``== != < <= > >=``), ``|``, ``^``, ``&``, ``+ -``
and ``..`` (string concatenation), ``* /``, then ``!``, ``-`` and ``~``. Statements are separated by
``;``; a script's value is its last statement's.

Example::

    >>> board = {}
    >>> run = parse("count := 3; count += 2; msg := 'n=' .. count; count > 4 && msg != ''")
    >>> run(board), board
    (True, {'count': 5, 'msg': 'n=5'})
    >>> parse("half := 5 / 2; 'h=' .. half")(board)           # as BT.CPP writes a double
    'h=2.500000'
    >>> parse("x := (1 + 2) * 4 / 3")(board), parse("x == 4 ? 'four' : 'other'")(board)
    (4.0, 'four')
    >>> parse("x := ")
    Traceback (most recent call last):
    ...
    thymio_bt.behaviours.btcpp_script.ScriptError: expected a value at the end of the script
"""

from __future__ import annotations

import re
from collections.abc import Callable, MutableMapping
from typing import Any

Board = MutableMapping[str, Any]
Script = Callable[[Board], Any]

_TOKEN = re.compile(
    r"\s*(?:(?P<num>0x[0-9a-fA-F]+|\d+\.\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?|\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<str>'[^']*'|\"[^\"]*\")"
    r"|(?P<name>[A-Za-z_@][A-Za-z0-9_.@]*(?<!\.))"
    r"|(?P<op>:=|\+=|-=|\*=|/=|==|!=|<=|>=|&&|\|\||\.\.|[-+*/<>!?:;()=&|^~]))"
)
_ASSIGN = (":=", "=", "+=", "-=", "*=", "/=")
_COMPARE = ("==", "!=", "<", "<=", ">", ">=")


class ScriptError(ValueError):
    """A script that does not parse, or that fails as it runs (a missing entry, a wrong type)."""


def tokenize(text: str) -> list[tuple[str, Any]]:
    """The script's tokens: (kind, value) with kind ``num``, ``str``, ``name`` or ``op``."""
    tokens: list[tuple[str, Any]] = []
    position = 0
    text = text.rstrip()
    while position < len(text):
        match = _TOKEN.match(text, position)
        if match is None or match.end() == position:
            raise ScriptError(f"unexpected character {text[position:].lstrip()[:1]!r} at column {position + 1}")
        kind = match.lastgroup or ""
        value: Any = match.group(kind)
        if kind == "num":
            value = (
                int(value, 16)
                if value.startswith("0x")
                else float(value)
                if "." in value or "e" in value.lower()
                else int(value)
            )
        elif kind == "str":
            value = value[1:-1]
        tokens.append((kind, value))
        position = match.end()
    return tokens


def parse(text: str, enums: dict[str, int] | None = None) -> Script:
    """The script as a function of the blackboard (a mapping) that returns the script's value."""
    parser = _Parser(tokenize(text), enums or {})
    statements = [parser.assignment()]
    while parser.accept(";"):
        if parser.at_end():
            break
        statements.append(parser.assignment())
    if not parser.at_end():
        raise ScriptError(f"unexpected {parser.peek()[1]!r}")

    def run(board: Board) -> Any:
        value = None
        for statement in statements:
            value = statement(board)
        return value

    return run


def truth(value: Any) -> bool:
    """A value as a condition: BT.CPP casts numbers and booleans (a string is an error)."""
    if isinstance(value, str):
        raise ScriptError(f"the string '{value}' is not a condition")
    return bool(value)


def _number(value: Any) -> Any:
    """A value as a number for arithmetic (a string of a number converts, as in BT.CPP)."""
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, (int, float)):
        return value
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ScriptError(f"'{value}' is not a number") from None


def _compare(op: str, left: Any, right: Any) -> bool:
    """A comparison; a string beside a number is read as a number."""
    if isinstance(left, str) != isinstance(right, str) or not isinstance(left, str):
        left, right = _number(left), _number(right)
    if op == "==":
        return bool(left == right)
    if op == "!=":
        return bool(left != right)
    try:
        return bool({"<": left < right, "<=": left <= right, ">": left > right, ">=": left >= right}[op])
    except TypeError:
        raise ScriptError(f"cannot compare '{left}' and '{right}'") from None


def _arith(op: str, left: Any, right: Any) -> Any:
    """``+ - * /`` and the bitwise operators on numbers."""
    a, b = _number(left), _number(right)
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        if b == 0:
            raise ScriptError("division by zero")
        return a / b
    if isinstance(a, float) or isinstance(b, float):
        raise ScriptError(f"'{op}' needs whole numbers")
    return {"&": a & b, "|": a | b, "^": a ^ b}[op]


class _Parser:
    """Recursive descent over the tokens; each method returns a closure of the board."""

    def __init__(self, tokens: list[tuple[str, Any]], enums: dict[str, int]) -> None:
        self.tokens, self.enums, self.index = tokens, enums, 0

    def peek(self) -> tuple[str, Any]:
        return self.tokens[self.index] if self.index < len(self.tokens) else ("end", None)

    def at_end(self) -> bool:
        return self.index >= len(self.tokens)

    def accept(self, *ops: str) -> str | None:
        kind, value = self.peek()
        if kind == "op" and value in ops:
            self.index += 1
            return str(value)
        return None

    def expect(self, op: str) -> None:
        if not self.accept(op):
            found = self.peek()[1]
            raise ScriptError(f"expected '{op}'" + (f", found {found!r}" if found is not None else " at the end"))

    def assignment(self) -> Script:
        kind, name = self.peek()
        if kind == "name" and self.index + 1 < len(self.tokens):
            op = self.tokens[self.index + 1]
            if op[0] == "op" and op[1] in _ASSIGN:
                if name in self.enums or name in ("true", "false"):
                    raise ScriptError(f"cannot assign to '{name}'")
                self.index += 2
                value = self.assignment()
                return _assign(str(name), str(op[1]), value)
        return self.ternary()

    def ternary(self) -> Script:
        condition = self.binary(0)
        if not self.accept("?"):
            return condition
        then = self.ternary()
        self.expect(":")
        other = self.ternary()
        return lambda b: then(b) if truth(condition(b)) else other(b)

    _LEVELS: tuple[tuple[str, ...], ...] = (
        ("||",),
        ("&&",),
        _COMPARE,
        ("|",),
        ("^",),
        ("&",),
        ("+", "-", ".."),
        ("*", "/"),
    )

    def binary(self, level: int) -> Script:
        if level == len(self._LEVELS):
            return self.unary()
        left = self.binary(level + 1)
        ops = self._LEVELS[level]
        if ops is _COMPARE:
            return self._comparisons(left, level)
        while (op := self.accept(*ops)) is not None:
            right = self.binary(level + 1)
            left = _combine(op, left, right)
        return left

    def _comparisons(self, first: Script, level: int) -> Script:
        """``a < b <= c``: each pair compared, all must hold (BT.CPP chains comparisons)."""
        operands, ops = [first], []
        while (op := self.accept(*_COMPARE)) is not None:
            ops.append(op)
            operands.append(self.binary(level + 1))
        if not ops:
            return first

        def chain(b: Board) -> bool:
            values = [operand(b) for operand in operands]
            return all(_compare(op, values[i], values[i + 1]) for i, op in enumerate(ops))

        return chain

    def unary(self) -> Script:
        op = self.accept("!", "-", "~")
        if op is None:
            return self.primary()
        inner = self.unary()
        if op == "!":
            return lambda b: not truth(inner(b))
        if op == "-":
            return lambda b: -_number(inner(b))
        return lambda b: ~int(_number(inner(b)))

    def primary(self) -> Script:
        kind, value = self.peek()
        if kind == "end":
            raise ScriptError("expected a value at the end of the script")
        self.index += 1
        if kind in ("num", "str"):
            return lambda b: value
        if kind == "name":
            if value in ("true", "false"):
                flag = value == "true"
                return lambda b: flag
            if value in self.enums:
                number = self.enums[value]
                return lambda b: number
            return _read(str(value))
        if value == "(":
            inner = self.assignment()
            self.expect(")")
            return inner
        raise ScriptError(f"expected a value, found {value!r}")


def _combine(op: str, left: Script, right: Script) -> Script:
    """A binary operator's closure (``&&`` and ``||`` short-circuit)."""
    if op == "&&":
        return lambda b: truth(left(b)) and truth(right(b))
    if op == "||":
        return lambda b: truth(left(b)) or truth(right(b))
    if op == "..":
        return lambda b: _text(left(b)) + _text(right(b))
    return lambda b: _arith(op, left(b), right(b))


def _text(value: Any) -> str:
    """A value in a string concatenation."""
    if isinstance(value, (bool, float)):
        return f"{float(value):f}"  # BT.CPP writes numbers it computed with std::to_string
    return str(value)


def _read(name: str) -> Script:
    """A blackboard entry's value (an error when there is none)."""

    def read(board: Board) -> Any:
        if name not in board:
            raise ScriptError(f"the blackboard has no entry '{name}'")
        return board[name]

    return read


def _typed(name: str, old: Any, new: Any) -> Any:
    """``new`` as the type of the entry it replaces: BT.CPP keeps a whole-number entry whole (a
    fraction is an error), like ``v := 0; v := 2.5``."""
    if isinstance(old, int) and not isinstance(old, bool) and isinstance(new, float):
        if not new.is_integer():
            raise ScriptError(f"'{name}' holds a whole number: cannot assign {new:g} to it")
        return int(new)
    return new


def _assign(name: str, op: str, value: Script) -> Script:
    """An assignment's closure: its value is the value written."""

    def assign(board: Board) -> Any:
        new = value(board)
        if op != ":=" and name not in board:
            raise ScriptError(f"'{name}' is not on the blackboard: create it with '{name} := ...'")
        if op in ("+=", "-=", "*=", "/="):
            current = board[name]
            text = op == "+=" and isinstance(current, str)
            new = current + _text(new) if text else _arith(op[0], current, new)
        elif op == "=" and name in board and isinstance(board[name], (int, float)) and isinstance(new, str):
            new = _number(new)
        board[name] = _typed(name, board.get(name), new)
        return new

    return assign
