"""Author mazes of square cells quickly as ASCII art.

Corners are ``+``, horizontal walls ``-`` runs between corners, vertical walls ``|`` on corner
columns; a cell may hold ``>``, ``<``, ``^`` or ``v`` to add a ``start`` spawn with base_link at the
cell centre facing that way (the course's convention). The bottom-left corner is ``origin``.

Example::

    >>> maze = maze_from_grid('''
    ... +--+--+
    ... |>    |
    ... +--+  +
    ...    |  |
    ...    +--+
    ... ''', cell=0.2)
    >>> len(maze.walls), maze.spawn("start")         # collinear walls joined into one
    (6, Pose(x=0.1, y=0.3, yaw=0.0))
"""

from __future__ import annotations

import math
from itertools import pairwise
from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.fields import Length, Point
from thymio_bt.maze.model import Maze, Spawn, Wall

_HEADINGS = {">": 0.0, "^": math.pi / 2, "<": math.pi, "v": -math.pi / 2}


def maze_from_grid(
    text: str,
    cell: float = 0.2,
    origin: tuple[float, float] = (0.0, 0.0),
    thickness: float = 0.01,
    name: str = "grid",
    filename: str = "<grid>",
    first_line: int = 1,
    first_col: int = 1,
) -> Maze:
    """Build a :class:`Maze` from ASCII art; bad art is a :class:`UserError` pointing at the line and
    column (``first_line``/``first_col``: where the art starts in its file).

    >>> maze = maze_from_grid('''
    ... +--+--+
    ... |>    |
    ... +--+--+
    ... ''', cell=0.2)
    >>> len(maze.walls), maze.spawns["start"].pose()
    (4, Pose(x=0.1, y=0.1, yaw=0.0))
    """
    lines = [ln.rstrip() for ln in text.splitlines()]
    while lines and not lines[0].strip():
        lines.pop(0)
        first_line += 1
    while lines and not lines[-1].strip():
        lines.pop()
    art = _Art(lines, cell, origin, thickness, filename, first_line, first_col)
    for r, line in enumerate(lines):
        if r % 2 == 0:
            art.corner_line(r, line)
        else:
            art.cell_line(r, line)
    return Maze(name=name, walls=_merge(art.walls), spawns=art.spawns)


class _Art:
    """The walls and spawns of ASCII art, read line by line (see :func:`maze_from_grid`)."""

    def __init__(
        self,
        lines: list[str],
        cell: float,
        origin: tuple[float, float],
        thickness: float,
        filename: str,
        first_line: int,
        first_col: int,
    ) -> None:
        self.cell, self.origin, self.thickness = cell, origin, thickness
        self.filename, self.first_line, self.first_col = filename, first_line, first_col
        self.corner_cols, self.width = self._corners(lines)
        self.base = self.corner_cols[0]
        self.n_rows = (len(lines) - 1) // 2
        self.walls: list[Wall] = []
        self.spawns: dict[str, Spawn] = {}

    def _error(self, message: str, line: int, col: int, hint: str) -> UserError:
        """A :class:`UserError` at ``line`` and ``col`` of the art (0-based), in its file."""
        return UserError(Problem(message, self.filename, self.first_line + line, self.first_col + col, hint=hint))

    def _corners(self, lines: list[str]) -> tuple[list[int], int]:
        """The columns of the '+' corners and the cells' width, checked: an odd number of lines,
        two corners or more, evenly spaced."""
        if len(lines) < 3 or len(lines) % 2 == 0:
            raise self._error(
                "a grid needs an odd number of lines (corner lines around cell lines)",
                0,
                0,
                "start and end with a '+--+' line",
            )
        corner_cols = sorted({i for ln in lines[::2] for i, ch in enumerate(ln) if ch == "+"})
        if len(corner_cols) < 2:
            raise self._error("no '+' corners found", 0, 0, "draw cells between '+' corners, e.g. '+--+--+'")
        widths = {b - a for a, b in pairwise(corner_cols)}
        if len(widths) != 1:
            raise self._error(
                "corners '+' must be evenly spaced", 0, 0, "every cell must be drawn the same width, e.g. '+--+--+'"
            )
        return corner_cols, widths.pop()

    def _x(self, col: int) -> float:
        """The x of the corner column ``col``."""
        return round(self.origin[0] + (col - self.base) // self.width * self.cell, 9)

    def corner_line(self, r: int, line: str) -> None:
        """Line ``r``, of corners: its horizontal walls."""
        cell, width = self.cell, self.width
        y_corner = round(self.origin[1] + (self.n_rows - r // 2) * cell, 9)
        for col in self.corner_cols[:-1]:
            seg = line[col + 1 : col + width] if col + 1 < len(line) else ""
            if seg.strip("-") == "" and seg.count("-") == width - 1:
                x0 = self._x(col)
                self.walls.append(
                    Wall(start=(x0, y_corner), end=(round(x0 + cell, 9), y_corner), thickness=self.thickness)
                )
            elif seg.strip():
                raise self._error(
                    f"unexpected '{seg.strip()}' in a corner line", r, col + 1, "use '-' for walls, spaces for gaps"
                )

    def cell_line(self, r: int, line: str) -> None:
        """Line ``r``, of cells: its vertical walls, and the start arrow of a cell that holds one."""
        cell, width = self.cell, self.width
        y0 = round(self.origin[1] + (self.n_rows - 1 - r // 2) * cell, 9)
        for col in self.corner_cols:
            ch = line[col] if col < len(line) else " "
            if ch == "|":
                x = self._x(col)
                self.walls.append(Wall(start=(x, y0), end=(x, round(y0 + cell, 9)), thickness=self.thickness))
            elif ch not in " ":
                raise self._error(f"unexpected '{ch}' on a wall column", r, col, "use '|' for a wall or a space")
        for i, col in enumerate(self.corner_cols[:-1]):
            inside = line[col + 1 : col + width]
            stray = next((k for k, ch in enumerate(inside) if ch != " " and ch not in _HEADINGS), None)
            if stray is not None:
                raise self._error(
                    f"unexpected '{inside[stray]}' inside a cell",
                    r,
                    col + 1 + stray,
                    "a cell holds spaces, or one of > < ^ v for the start",
                )
            marks = [ch for ch in inside if ch in _HEADINGS]
            if marks:
                cx, cy = round(self.origin[0] + (i + 0.5) * cell, 9), round(y0 + cell / 2, 9)
                self.spawns["start"] = Spawn(x=cx, y=cy, yaw=_HEADINGS[marks[0]])


def _merge(walls: list[Wall]) -> list[Wall]:
    """Join collinear walls that touch end to end, so long walls are one box (as in Gazebo)."""
    horizontal: dict[float, list[tuple[float, float]]] = {}
    vertical: dict[float, list[tuple[float, float]]] = {}
    thickness = walls[0].thickness if walls else 0.01
    for w in walls:
        (x0, y0), (x1, y1) = w.start, w.end
        if abs(y0 - y1) < 1e-12:
            horizontal.setdefault(round(y0, 9), []).append((min(x0, x1), max(x0, x1)))
        else:
            vertical.setdefault(round(x0, 9), []).append((min(y0, y1), max(y0, y1)))
    merged: list[Wall] = []
    for table, make in (
        (horizontal, lambda c, a, b: Wall(start=(a, c), end=(b, c), thickness=thickness)),
        (vertical, lambda c, a, b: Wall(start=(c, a), end=(c, b), thickness=thickness)),
    ):
        for coord in sorted(table):
            spans = sorted(table[coord])
            a, b = spans[0]
            for s, e in spans[1:]:
                if s <= b + 1e-9:
                    b = max(b, e)
                else:
                    merged.append(make(coord, a, b))
                    a, b = s, e
            merged.append(make(coord, a, b))
    return merged


class GridMazeFile(BaseModel):
    """The keys of a maze file in the grid form; the art itself is read by :mod:`.grid`."""

    model_config = ConfigDict(extra="forbid")
    name: str = "grid"
    description: str = ""
    grid: str = Field(description="the maze as ASCII art: 'grid: |' then '+--+' lines")
    cell: Annotated[Length, Field(gt=0, le=10)] = 0.2
    origin: Point = (0.0, 0.0)
    thickness: Annotated[Length, Field(gt=0, le=1.0)] = 0.01
    spawns: dict[str, Spawn] = Field(default={})


def maze_from_grid_file(header: GridMazeFile, mark: tuple[int, int], filename: str) -> Maze:
    """The maze of a validated grid-form file; ``mark`` is where the ``grid:`` value starts, so
    errors in the art point at the file's own line and column (a ``grid: |`` block is indented)."""
    line, col = mark
    if "\n" in header.grid:  # a block: the art starts on the next line
        line += 1
        try:
            source = Path(filename).read_text(encoding="utf-8").splitlines()[line - 1 :]
        except OSError:
            source = []
        first = next((text for text in source if text.strip()), "")
        col = len(first) - len(first.lstrip(" ")) + 1
    maze = maze_from_grid(
        header.grid,
        cell=header.cell,
        origin=header.origin,
        thickness=header.thickness,
        name=header.name,
        filename=filename,
        first_line=line,
        first_col=col,
    )
    return maze.model_copy(update={"spawns": {**maze.spawns, **header.spawns}, "description": header.description})
