"""User errors: problems a user can cause, reported as ``file:line:col: message (hint)``; and the
root of every thymio-bt exception, :class:`ThymioBtError`.

Every loader collects :class:`Problem` s and raises one :class:`UserError` holding all of them, so
a student sees every mistake of a file at once. The CLI prints them and exits with code 2.

Example:

>>> hint = did_you_mean("MoveUntillWall", ["MoveUntilWall", "Stop"])
>>> error = UserError([
...     Problem("unknown node 'MoveUntillWall'", "m.yaml", 12, 7, "tree", hint),
...     Problem("time_limit must be > 0", "m.yaml", 4),
... ])
>>> print(error)
m.yaml:12:7: unknown node 'MoveUntillWall' [at tree] (hint: did you mean 'MoveUntilWall'?)
m.yaml:4:1: time_limit must be > 0
>>> type_name([1]), type_name(None), type_name(True)
('a list', 'nothing', 'true/false')
"""

from __future__ import annotations

import difflib
import importlib
from collections.abc import Iterable
from dataclasses import dataclass
from types import ModuleType
from typing import Any


@dataclass(frozen=True, slots=True)
class Problem:
    """One problem at one place of a file (line and column are 1-based; 0 when unknown)."""

    message: str
    file: str = ""
    line: int = 0
    column: int = 0
    path: str = ""
    hint: str = ""

    def __str__(self) -> str:
        where = self.file
        if self.file and self.line:
            where += f":{self.line}:{self.column or 1}"
        text = f"{where}: {self.message}" if where else self.message
        if self.path:
            text += f" [at {self.path}]"
        if self.hint:
            text += f" (hint: {self.hint})"  # one line per problem: the CLI contract
        return text


class ThymioBtError(Exception):
    """The root of every exception thymio-bt raises (docs/architecture.md lists them): ``except
    ThymioBtError`` catches them all, and each keeps its standard base (``UnitError`` is still a
    ``ValueError``). Signals that end a command are ``KeyboardInterrupt`` s instead, out of reach
    of ``except Exception``."""


class UserError(ThymioBtError):
    """One or more problems the user can fix; never a bug of thymio-bt."""

    def __init__(self, problems: Iterable[Problem] | Problem | str):
        if isinstance(problems, str):
            problems = [Problem(problems)]
        elif isinstance(problems, Problem):
            problems = [problems]
        self.problems: list[Problem] = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class StopRun(ThymioBtError):
    """Raised by a tick hook (:mod:`thymio_bt.run.runner`) to end the run there (e.g. the user closed
    the viewer): the run ends as a FAILURE with code STOPPED and the message as its reason, with its
    report and log intact. Here, at the bottom, so that a hook of a lower room (the log's
    :class:`~thymio_bt.logs.recording.Recorder`) may raise it."""


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """A 'did you mean X?' hint for a misspelt name, or a list of the valid names."""
    options = sorted(set(choices))
    close = difflib.get_close_matches(word, options, n=1, cutoff=0.6)
    if close:
        return f"did you mean '{close[0]}'?"
    shown = ", ".join(options[:12]) + (", ..." if len(options) > 12 else "")
    return f"expected one of: {shown}"


def type_name(value: Any) -> str:
    """How a YAML value's type is named in messages: 'a mapping', 'a list', 'true/false', ..."""
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if value is None:
        return "nothing"
    return type(value).__name__


def optional_module(name: str, needed_by: str, hint: str) -> ModuleType:
    """``import name`` for what an optional extra brings: a :class:`UserError` saying who needs it and
    how to get it, instead of an ImportError, when it is not installed.

    Example:

    >>> optional_module("json", "the report", "it comes with Python").dumps([1])
    '[1]'
    >>> optional_module("no_such_module", "the 'tdm' backend", "pip install 'thymio-bt[thymio]'")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: the 'tdm' backend needs no_such_module, which is not installed \
(No module named 'no_such_module') (hint: pip install 'thymio-bt[thymio]')
    """
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise UserError(
            Problem(f"{needed_by} needs {name.partition('.')[0]}, which is not installed ({exc})", hint=hint)
        ) from None


__all__ = ["Problem", "StopRun", "ThymioBtError", "UserError", "did_you_mean", "optional_module", "type_name"]
