"""Parsing a user's XML file (a Gazebo world, a BT.CPP mission) with the same guards everywhere.

expat is driven directly so every element knows its line and column, and so that nothing a file
says can cost more than its size: DOCTYPE and ENTITY declarations are refused (no "billion laughs",
nothing fetched), elements may nest :data:`MAX_DEPTH` deep at most (a deeper file would overflow the
recursion of whoever walks the tree), and every expat or encoding error is one located message.
The caller builds its own tree from ``start(tag, attrs, line, column)`` and ``end(tag)`` calls.

>>> seen = []
>>> parse_xml(b"<sdf><world/></sdf>", "w.world", "world", lambda tag, attrs, line, col: seen.append((tag, line, col)))
>>> seen
[('sdf', 1, 1), ('world', 1, 6)]
>>> parse_xml(b"<a>" * 201, "deep.xml", "world", lambda *args: None)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: deep.xml:1:601: the world is nested deeper than 200 levels
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any
from xml.parsers import expat

from thymio_bt.errors import Problem, UserError

#: the deepest element nesting read (the course's worlds nest 6 deep, a mission's tree tens)
MAX_DEPTH = 200

StartHandler = Callable[[str, dict[str, str], int, int], None]


def parse_xml(
    data: bytes,
    file: str,
    what: str,
    start: StartHandler,
    end: Callable[[str], object] | None = None,
    text: Callable[[str], None] | None = None,
    hint: str = "",
) -> None:
    """Parse ``data`` (the content of ``file``, a ``what``), calling ``start`` for each element with
    its line and 1-based column, ``end`` as it closes and ``text`` with its character data; ``hint``
    goes with a syntax error."""
    parser = expat.ParserCreate()
    depth = 0

    def where() -> tuple[int, int]:
        return parser.CurrentLineNumber, parser.CurrentColumnNumber + 1

    def refuse(*_: Any) -> None:
        raise UserError(
            Problem(
                f"DOCTYPE and ENTITY declarations are not allowed in a {what}",
                file,
                *where(),
                hint="remove the <!DOCTYPE ...> block: the file never needs it",
            )
        )

    def on_start(tag: str, attrs: dict[str, str]) -> None:
        nonlocal depth
        depth += 1
        if depth > MAX_DEPTH:
            raise UserError(Problem(f"the {what} is nested deeper than {MAX_DEPTH} levels", file, *where()))
        start(tag, attrs, *where())

    def on_end(tag: str) -> None:
        nonlocal depth
        depth -= 1
        if end is not None:
            end(tag)

    parser.buffer_text = True
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    parser.StartElementHandler = on_start
    parser.EndElementHandler = on_end
    if text is not None:
        parser.CharacterDataHandler = text
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        message = f"not a valid XML file: {expat.errors.messages[exc.code]}"
        raise UserError(Problem(message, file, exc.lineno, exc.offset + 1, hint=hint)) from None
    except (LookupError, ValueError) as exc:  # an encoding expat does not know, e.g. EBCDIC
        raise UserError(
            Problem(
                f"cannot read the XML: {exc}",
                file,
                1,
                1,
                hint=f'save the {what} as UTF-8 (<?xml version="1.0" encoding="UTF-8"?>)',
            )
        ) from None
