"""What every pass of the mission loader shares: the problems found so far, where each value was
written (file:line:col from the YAML marks), and how a number with a unit or a pose is read.

The loader reports every problem of a mission at once, so a pass never stops at the first: it
records a :class:`Problem` and goes on (see :mod:`thymio_bt.mission.loader`).

Example::

    >>> loader_pass = LoaderPass([])
    >>> loader_pass.quantity("$side * 2", Scope({"side": Quantity(0.25, "length")}), ("m.yaml", 3, 9), "d", "length")
    0.5
    >>> loader_pass.quantity("5cm", Scope({}), ("m.yaml", 4, 9), "angle", "angle") is None
    True
    >>> print(loader_pass.problems[0])
    m.yaml:4:9: expected an angle (in rad), got a length [at angle] (hint: write an angle: 90deg, pi/2 or 1.57 rad)
"""

from __future__ import annotations

import math
import typing
from collections.abc import Iterable, Mapping
from typing import Any

from thymio_bt.errors import Problem, did_you_mean, type_name
from thymio_bt.geometry import Pose
from thymio_bt.inputs.fields import key_hint
from thymio_bt.inputs.units import Quantity, UnitError, parse_kind, parse_pose, parse_value
from thymio_bt.inputs.yamlio import MarkedDict, MarkedList, mark_of
from thymio_bt.maze import Maze

Where = tuple[str, int, int]


class Scope:
    """Parameter values visible at one place: mission parameters, overlaid by a subtree's."""

    def __init__(self, values: Mapping[str, Any], parent: Scope | None = None) -> None:
        self.values = dict(values)
        self.parent = parent

    def get(self, name: str) -> Any:
        """The value of parameter ``name``, the innermost scope's first; ``KeyError`` when none has it."""
        if name in self.values:
            return self.values[name]
        if self.parent is not None:
            return self.parent.get(name)
        raise KeyError(name)

    def names(self) -> set[str]:
        """Every parameter name visible here (for 'did you mean' hints)."""
        return set(self.values) | (self.parent.names() if self.parent else set())


class LoaderPass:
    """The base of each pass of the mission loader: collects :class:`Problem` s for one mission load
    and reads values where they were written."""

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems

    def problem(self, message: str, where: Where, path: str = "", hint: str = "") -> None:
        """Record a problem at ``where`` (file, line, column), with the node path and a hint."""
        self.problems.append(Problem(message, where[0], where[1], where[2], path, hint))

    def adopt(self, problems: Iterable[Problem], where: Where, path: str) -> None:
        """Take the problems another loader found (a maze, an include, a robot profile): one that has
        no line of its own (a missing or unreadable file) is put where the file was named."""
        self.problems.extend(p if p.line else Problem(p.message, *where, path, p.hint) for p in problems)

    @staticmethod
    def where_key(data: Any, key: Any, file: str) -> Where:
        """The place of ``key`` in the mapping ``data`` (the mapping's own when it has no marks)."""
        if isinstance(data, MarkedDict) and key in data.marks:
            return (file, *data.marks[key])
        return (file, *mark_of(data))

    @staticmethod
    def where_value(data: Any, key: Any, file: str) -> Where:
        """The place of the value of ``data[key]`` (a mapping's key or a list's index), else ``data``'s own."""
        if isinstance(data, MarkedDict) and key in data.value_marks:
            return (file, *data.value_marks[key])
        if isinstance(data, MarkedList) and isinstance(key, int) and key < len(data.marks):
            return (file, *data.marks[key])
        return (file, *mark_of(data))

    @staticmethod
    def where_item(items: Any, index: int, where: Where) -> Where:
        """The place of ``items[index]`` when the list carries marks, else ``where`` (the list's)."""
        if isinstance(items, MarkedList) and index < len(items.marks):
            return (where[0], *items.marks[index])
        return where

    def check_keys(
        self, data: MarkedDict, allowed: typing.Iterable[str], file: str, path: str, what: str, model: Any = None
    ) -> None:
        """A problem for each key of ``data`` not in ``allowed`` (``what``: 'the mission', 'a subtree'...);
        ``model``: the parameter model whose values a key may be meant as (``times: forever``)."""
        allowed = list(allowed)
        for key in data:
            if key not in allowed:
                self.problem(
                    f"unknown key '{key}' in {what}",
                    self.where_key(data, key, file),
                    path,
                    key_hint(str(key), model, allowed) if model is not None else did_you_mean(str(key), allowed),
                )

    def quantity(self, value: Any, scope: Scope, where: Where, path: str, kind: str | None) -> float | None:
        """Parse a number-with-unit or expression in ``scope``; None (and a problem) when it fails."""
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            self.problem(
                f"expected a number, got {type_name(value)}",
                where,
                path,
                "write a number, optionally with a unit: 0.1, 10cm/s, pi/2, 90deg",
            )
            return None

        def resolve(name: str) -> Quantity:
            try:
                raw = scope.get(name)
            except KeyError:
                raise UnitError(f"unknown parameter '${name}'", _parameter_hint(name, scope)) from None
            if isinstance(raw, Quantity):
                return raw
            if isinstance(raw, (int, float)) and not isinstance(raw, bool):
                return Quantity(float(raw))
            raise UnitError(f"parameter '${name}' is {raw!r}, not a number")

        try:
            return parse_kind(value, resolve, kind)
        except UnitError as exc:
            self.problem(
                str(exc),
                where,
                path,
                exc.hint or "numbers may carry a unit (5cm, 90deg, 0.1 m/s) and use + - * / ( ) pi and $parameters",
            )
            return None

    def parameter_value(self, value: Any, where: Where, path: str) -> Any:
        """A mission or subtree parameter default: a quantity when it parses, else the raw value."""
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return Quantity(float(value))
        if isinstance(value, str):
            try:
                return parse_value(value)
            except UnitError:
                return value
        if isinstance(value, bool):
            return value
        self.problem(
            f"a parameter must be a number, a string or true/false, got {type_name(value)}",
            where,
            path,
            "e.g. cruise: 10cm/s, side: pi/2, turn: bb:turn_angle or enabled: true",
        )
        return None

    def pose(self, raw: Any, where: Where, path: str, scope: Scope, maze: Maze | None) -> Pose | None:
        """A pose from ``[x, y, yaw]``, ``"x,y,yaw"`` or the name of a spawn of the maze."""
        if isinstance(raw, str) and "," not in raw:
            if maze is None:
                return None
            if raw in maze.spawns:
                return maze.spawns[raw].pose()
            self.problem(
                f"maze '{maze.name}' has no spawn named '{raw}'",
                where,
                path,
                did_you_mean(raw, maze.spawns) if maze.spawns else "give [x, y, yaw] instead",
            )
            return None
        if isinstance(raw, str):
            try:
                return self._heading(Pose(*parse_pose(raw)), where, path)
            except UnitError as exc:
                spawns = f"; the maze's spawns: {', '.join(maze.spawns)}" if maze and maze.spawns else ""
                self.problem(str(exc), where, path, (exc.hint + spawns) if exc.hint else "")
                return None
        if not isinstance(raw, list) or len(raw) != 3:
            spawns = f", or one of the maze's spawns: {', '.join(maze.spawns)}" if maze and maze.spawns else ""
            self.problem(
                "a pose is [x, y, yaw] or the name of a maze spawn",
                where,
                path,
                "e.g. [0.5, 0.3, pi/2] or [50cm, 30cm, 90deg]" + spawns,
            )
            return None
        parts = [
            self.quantity(v, scope, self.where_item(raw, i, where), path, kind)
            for i, (v, kind) in enumerate(zip(raw, ("length", "length", "angle"), strict=True))
        ]
        if any(p is None for p in parts):
            return None
        return self._heading(Pose(*parts), where, path)  # type: ignore[arg-type]

    def _heading(self, pose: Pose, where: Where, path: str) -> Pose | None:
        """The pose with its yaw in [-pi, pi] (exactly as given when it already is); a yaw of more
        than ten turns is surely a mistake (degrees written as radians, a stray exponent)."""
        if abs(pose.yaw) > MAX_YAW:
            self.problem(
                f"yaw {pose.yaw:g} rad is more than ten turns",
                where,
                path,
                "give a heading such as 90deg, pi/2 or -45deg",
            )
            return None
        # a yaw already in range must reach the robot as written, and wrap_angle is not the identity
        # there (it gives 0.2999999999999998 for 0.3, and -pi for a west-facing pi, whose sine has the
        # other sign); math.remainder is exact, into [-pi, pi]: so not wrap_angle
        return Pose(pose.x, pose.y, math.remainder(pose.yaw, math.tau))


#: the largest |yaw| accepted in a pose (rad): ten turns
MAX_YAW = 10 * math.tau


def _parameter_hint(name: str, scope: Scope) -> str:
    """The hint for an unknown ``$name``: the nearest name in scope, or how to declare one."""
    names = scope.names()
    if not names:
        return "no parameters are defined here: declare it under 'parameters:'"
    return did_you_mean(name, names)
