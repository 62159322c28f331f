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

    >>> from thymio_bt.maze import resolve_maze
    >>> maze = read_micromouse(resolve_maze("micromouse_4x4"))        # classic sizes: 18 cm cells
    >>> maze.description, maze.spawn("start")
    ('micromouse maze, 4 x 4 cells of 18 cm', Pose(x=0.09, y=0.09, yaw=1.5707963267948966))
    >>> maze.goal
    [Area(start=(0.0, 0.54), end=(0.18, 0.72))]
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
    """The cells and walls of a maze in the text format; every problem is located (file:line:col).

    >>> cells = parse_micromouse("o---o---o\\n| G     |\\no   o   o\\n| S |   |\\no---o---o\\n")
    >>> cells.cols, cells.rows, cells.start, sorted(cells.goal), cells.open_sides(0, 0)
    (2, 2, (0, 0), [(0, 1)], ['N'])
    """
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
    text_maze = _TextMaze(file, first, width, (width - 1) // 4, (len(lines) - 1) // 2)
    for n, line in enumerate(lines):
        text_maze.read_line(n, line)
    return text_maze.cells()


class _TextMaze:
    """What the lines of a maze in the text format say, read one at a time, and their problems."""

    def __init__(self, file: str, first: int, width: int, cols: int, rows: int) -> None:
        #: the file, the index of its first line of the maze, and that line's width
        self.file, self.first, self.width = file, first, width
        self.cols, self.rows = cols, rows
        self.problems: list[Problem] = []
        self.horizontal: set[tuple[int, int]] = set()
        self.vertical: set[tuple[int, int]] = set()
        self.goal: set[tuple[int, int]] = set()
        self.start: tuple[int, int] | None = None

    def _problem(self, message: str, line: int, col: int, hint: str = "") -> None:
        """Record a problem at ``line`` (1-based, in the file) and ``col`` (1-based)."""
        self.problems.append(Problem(message, self.file, line, col, hint=hint))

    def read_line(self, n: int, line: str) -> None:
        """The maze's line ``n``: posts and horizontal walls (even lines), or cells and vertical walls."""
        where = self.first + n + 1
        if len(line) > self.width:
            self._problem(
                f"this line has {len(line)} characters, the first has {self.width}",
                where,
                self.width + 1,
                "every line of the maze is as long as the first",
            )
            return
        line = line.ljust(self.width)  # trailing blanks may have been trimmed
        j = self.rows - 1 - n // 2  # the cell row below a post row, or this cell row
        for col, char in enumerate(line):
            if n % 2 == 0:
                self._post_row(line, where, j, col, char)
            else:
                self._cell_row(where, j, col, char)

    def _post_row(self, line: str, where: int, j: int, col: int, char: str) -> None:
        """One character of a row of posts and horizontal walls (the walls on the north of row ``j``)."""
        if col % 4 == 0:
            if char != "o":
                self._problem(f"a post 'o' is missing here, found {char!r}", where, col + 1)
        elif col % 4 == 1:
            segment = line[col : col + 3]
            if segment == "---":
                self.horizontal.add((col // 4, j + 1))
            elif segment.strip():
                self._problem(f"a horizontal wall is '---' or blanks, found {segment!r}", where, col + 1)

    def _cell_row(self, where: int, j: int, col: int, char: str) -> None:
        """One character of a row of cells ``j``: a vertical wall, a cell's mark, or a blank."""
        if col % 4 == 0:
            if char == "|":
                self.vertical.add((col // 4, j))
            elif char != " ":
                self._problem(f"a vertical wall is '|' or a blank, found {char!r}", where, col + 1)
        elif col % 4 == 2 and char in "SGsg":
            if char in "Ss":
                if self.start is not None:
                    self._problem("a second start cell 'S'", where, col + 1)
                self.start = (col // 4, j)
            else:
                self.goal.add((col // 4, j))
        elif char != " ":
            self._problem(
                f"unexpected {char!r} in a cell", where, col + 1, "a cell holds S (start), G (goal) or nothing"
            )

    def _check_outline(self) -> None:
        """A problem for every missing wall on the maze's border."""
        open_outline = "the outline is open: a wall is missing on the maze's border"
        last, first = self.first + 2 * self.rows + 1, self.first
        for i in range(self.cols):
            for j, line_no in ((0, last), (self.rows, first + 1)):
                if (i, j) not in self.horizontal:
                    self._problem(open_outline, line_no, 4 * i + 2, "close the border with '---'")
        for j in range(self.rows):
            for i, col in ((0, 1), (self.cols, 4 * self.cols + 1)):
                if (i, j) not in self.vertical:
                    self._problem(open_outline, first + 2 * (self.rows - 1 - j) + 2, col, "close the border with '|'")

    def cells(self) -> CellWalls:
        """The maze read, once every line is: a :class:`UserError` with all its problems if it has any."""
        self._check_outline()
        if self.start is None and not self.problems:
            self._problem("no start cell 'S'", self.first + 1, 1, "mark the start cell with S at its centre")
        if self.problems:
            raise UserError(self.problems)
        assert self.start is not None
        maze = CellWalls(
            self.cols,
            self.rows,
            frozenset(self.horizontal),
            frozenset(self.vertical),
            self.start,
            frozenset(self.goal),
        )
        if not maze.open_sides(*self.start):
            raise UserError(Problem("the start cell is closed on all four sides", self.file, self.first + 1, 1))
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
