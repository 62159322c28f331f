"""Micromouse contest mazes in their public text format, as mazes with a start and a goal region.

The format (the public collection of All Japan, APEC, UK... contest mazes)::

    o---o---o
    | G     |
    o   o   o
    | S |   |
    o---o---o

Every post is ``o``, a horizontal wall is ``---`` between two posts, a vertical wall ``|``; the
start cell holds ``S`` and each goal cell ``G`` at its centre character. Rows are written north
first. Coordinates: the origin is the centre of the bottom-left post, x to the right along the
columns, y up (the text's last line is y = 0), so cell (i, j) spans [i·c, (i+1)·c] × [j·c, (j+1)·c].
Walls are boxes ``wall`` thick from post centre to post centre (the maze format extends them by
half their thickness, which covers the posts); a post with no wall on it is a ``post`` square box.
The S cell becomes the spawn ``start`` facing its opening, the G cells the maze's goal region.

Example::

    maze = read_micromouse("mazes/micromouse_4x4.txt")        # classic sizes: 18 cm cells
    maze.spawns["start"], maze.goal
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import read_text
from thymio_bt.maze.model import Area, Maze, Obstacle, Spawn, Wall

#: the classic contest's dimensions (m): 18 cm cells, 12 mm walls on 12 mm posts
CELL, WALL, POST = 0.18, 0.012, 0.012
_HEADINGS = {"N": math.pi / 2, "E": 0.0, "S": -math.pi / 2, "W": math.pi}


@dataclass(frozen=True)
class CellWalls:
    """A maze as cells and the walls between them (the text format's content, before geometry)."""

    cols: int
    rows: int
    #: horizontal walls: (i, j) is the wall on the south side of cell (i, j); j in 0..rows
    horizontal: frozenset[tuple[int, int]]
    #: vertical walls: (i, j) is the wall on the west side of cell (i, j); i in 0..cols
    vertical: frozenset[tuple[int, int]]
    start: tuple[int, int]
    goal: frozenset[tuple[int, int]]

    def open_sides(self, i: int, j: int) -> list[str]:
        """The sides of cell (i, j) without a wall, in N, E, S, W order."""
        walls = {
            "N": (i, j + 1) in self.horizontal,
            "E": (i + 1, j) in self.vertical,
            "S": (i, j) in self.horizontal,
            "W": (i, j) in self.vertical,
        }
        return [side for side in "NESW" if not walls[side]]


def parse_micromouse(text: str, file: str = "") -> CellWalls:
    """The cells and walls of a maze in the text format; every problem is located (file:line:col)."""
    lines = [line.rstrip() for line in text.splitlines()]
    while lines and not lines[-1].strip():
        lines.pop()
    first = next((n for n, line in enumerate(lines) if line.strip()), None)
    if first is None:
        raise UserError(
            Problem("the maze file is empty", file, 1, 1, hint="posts 'o', walls '---' and '|', cells S and G")
        )
    lines = lines[first:]
    width = len(lines[0])
    if width < 5 or (width - 1) % 4 or len(lines) < 3 or len(lines) % 2 == 0:
        raise UserError(
            Problem(
                f"not a micromouse maze: {len(lines)} lines of {width} characters",
                file,
                first + 1,
                1,
                hint="each cell is 4 characters wide ('o---'), rows alternate posts and cells, "
                "and the last line is posts",
            )
        )
    cols, rows = (width - 1) // 4, (len(lines) - 1) // 2
    problems = []
    horizontal, vertical, goal = set(), set(), set()
    start = None
    for n, line in enumerate(lines):
        where = first + n + 1
        if len(line) > width:
            problems.append(
                Problem(
                    f"this line has {len(line)} characters, the first has {width}",
                    file,
                    where,
                    width + 1,
                    hint="every line of the maze is as long as the first",
                )
            )
            continue
        line = line.ljust(width)  # trailing blanks may have been trimmed
        j = rows - 1 - n // 2  # the cell row below a post row, or this cell row
        for col, char in enumerate(line):
            if n % 2 == 0:  # posts and horizontal walls
                if col % 4 == 0:
                    if char != "o":
                        problems.append(Problem(f"a post 'o' is missing here, found {char!r}", file, where, col + 1))
                elif col % 4 == 1:
                    segment = line[col : col + 3]
                    if segment == "---":
                        horizontal.add((col // 4, j + 1))
                    elif segment.strip():
                        problems.append(
                            Problem(f"a horizontal wall is '---' or blanks, found {segment!r}", file, where, col + 1)
                        )
            elif col % 4 == 0:  # vertical walls
                if char == "|":
                    vertical.add((col // 4, j))
                elif char != " ":
                    problems.append(Problem(f"a vertical wall is '|' or a blank, found {char!r}", file, where, col + 1))
            elif col % 4 == 2 and char in "SGsg":
                if char in "Ss":
                    if start is not None:
                        problems.append(Problem("a second start cell 'S'", file, where, col + 1))
                    start = (col // 4, j)
                else:
                    goal.add((col // 4, j))
            elif char != " ":
                problems.append(
                    Problem(
                        f"unexpected {char!r} in a cell",
                        file,
                        where,
                        col + 1,
                        hint="a cell holds S (start), G (goal) or nothing",
                    )
                )
    last = first + len(lines)
    for i in range(cols):
        for j, line_no in ((0, last), (rows, first + 1)):
            if (i, j) not in horizontal:
                problems.append(
                    Problem(
                        "the outline is open: a wall is missing on the maze's border",
                        file,
                        line_no,
                        4 * i + 2,
                        hint="close the border with '---'",
                    )
                )
    for j in range(rows):
        for i, col in ((0, 1), (cols, 4 * cols + 1)):
            if (i, j) not in vertical:
                problems.append(
                    Problem(
                        "the outline is open: a wall is missing on the maze's border",
                        file,
                        first + 2 * (rows - 1 - j) + 2,
                        col,
                        hint="close the border with '|'",
                    )
                )
    if start is None and not problems:
        problems.append(
            Problem("no start cell 'S'", file, first + 1, 1, hint="mark the start cell with S at its centre")
        )
    if problems:
        raise UserError(problems)
    assert start is not None
    maze = CellWalls(cols, rows, frozenset(horizontal), frozenset(vertical), start, frozenset(goal))
    if not maze.open_sides(*start):
        raise UserError(Problem("the start cell is closed on all four sides", file, first + 1, 1))
    return maze


def maze_from_cells(
    cells: CellWalls, name: str, cell: float = CELL, wall: float = WALL, post: float = POST, source: str = ""
) -> Maze:
    """The geometry of ``cells``: walls from post centre to post centre, free posts as small boxes."""
    walls, touched = [], set()
    for i, j in sorted(cells.horizontal):
        walls.append(Wall(start=(i * cell, j * cell), end=((i + 1) * cell, j * cell), thickness=wall))
        touched |= {(i, j), (i + 1, j)}
    for i, j in sorted(cells.vertical):
        walls.append(Wall(start=(i * cell, j * cell), end=(i * cell, (j + 1) * cell), thickness=wall))
        touched |= {(i, j), (i, j + 1)}
    posts = [
        Obstacle(center=(i * cell, j * cell), size=(post, post))
        for i in range(cells.cols + 1)
        for j in range(cells.rows + 1)
        if (i, j) not in touched
    ]
    si, sj = cells.start
    facing = cells.open_sides(si, sj)[0]
    spawn = Spawn(x=(si + 0.5) * cell, y=(sj + 0.5) * cell, yaw=_HEADINGS[facing])
    goal = [Area(start=(i * cell, j * cell), end=((i + 1) * cell, (j + 1) * cell)) for i, j in sorted(cells.goal)]
    return Maze(
        name=name,
        description=f"micromouse maze, {cells.cols} x {cells.rows} cells of {cell * 100:g} cm",
        source=source,
        walls=walls,
        obstacles=posts,
        spawns={"start": spawn},
        goal=goal,
    )


def read_micromouse(path: str | Path, cell: float = CELL, wall: float = WALL, post: float = POST) -> Maze:
    """Read a micromouse maze file (see the module docstring) as a :class:`Maze`."""
    path = Path(path)
    cells = parse_micromouse(read_text(path, "maze"), str(path))
    return maze_from_cells(cells, path.stem, cell, wall, post, source=str(path))


def to_text(cells: CellWalls) -> str:
    """``cells`` in the text format (what :func:`parse_micromouse` reads back)."""
    out = []
    for j in range(cells.rows, -1, -1):
        out.append("o" + "o".join("---" if (i, j) in cells.horizontal else "   " for i in range(cells.cols)) + "o")
        if j == 0:
            break
        row = j - 1
        line = ""
        for i in range(cells.cols + 1):
            line += "|" if (i, row) in cells.vertical else " "
            if i < cells.cols:
                mark = "S" if (i, row) == cells.start else "G" if (i, row) in cells.goal else " "
                line += f" {mark} "
        out.append(line.rstrip())
    return "\n".join(out) + "\n"
