"""Generated mazes of square cells, for tests and for trying missions on mazes they never saw.

- :func:`perfect_maze`: a random simply-connected maze (recursive backtracker) with an exit gap
  in its boundary, for wall following.
- :func:`path_maze`: a single corridor through given cells, closed at its far end: every turn is
  marked by a wall ahead with exactly one side open, like the course's bonus maze.

Example::

    >>> maze = perfect_maze(5, 4, seed=3)          # start spawn in the bottom-left cell
    >>> len(maze.walls), maze.spawn("start"), maze.description
    (29, Pose(x=0.1, y=0.1, yaw=0.0), 'random perfect maze, exit above cell (0, 3)')
    >>> path = [(0, 0), (1, 0), (1, 1), (2, 1)]
    >>> turns_along(path), len(path_maze(path).walls)
    ('LR', 10)
"""

from __future__ import annotations

import math
import random
from collections.abc import Set as AbstractSet
from itertools import pairwise
from typing import TYPE_CHECKING

from thymio_bt.maze.model import Maze, Spawn, Wall

if TYPE_CHECKING:
    from thymio_bt.maze.micromouse import CellWalls

Cell = tuple[int, int]
_STEPS = {(1, 0): 0.0, (0, 1): math.pi / 2, (-1, 0): math.pi, (0, -1): -math.pi / 2}


def _walls_from_open(
    cols: int,
    rows: int,
    passages: set[frozenset[Cell]],
    cell: float,
    thickness: float,
    inside: set[Cell] | None = None,
    gaps: AbstractSet[frozenset[Cell]] = frozenset(),
) -> list[Wall]:
    """A wall on every cell edge that is not a passage (only edges touching ``inside`` cells)."""
    inside = inside if inside is not None else {(c, r) for c in range(cols) for r in range(rows)}
    edges: set[tuple[int, int, str]] = set()  # (col, row, 'h'|'v'): lower/left edge of (col, row)
    for c, r in inside:
        for (dc, dr), kind, at in (
            ((0, -1), "h", (c, r)),
            ((0, 1), "h", (c, r + 1)),
            ((-1, 0), "v", (c, r)),
            ((1, 0), "v", (c + 1, r)),
        ):
            pair = frozenset({(c, r), (c + dc, r + dr)})
            if pair not in passages and pair not in gaps:
                edges.add((at[0], at[1], kind))
    walls = []
    for c, r, kind in sorted(edges):
        x, y = round(c * cell, 9), round(r * cell, 9)
        end = (round(x + cell, 9), y) if kind == "h" else (x, round(y + cell, 9))
        walls.append(Wall(start=(x, y), end=end, thickness=thickness))
    return walls


def _carve(
    rng: random.Random,
    cols: int,
    rows: int,
    stack: list[Cell],
    seen: set[Cell],
    passages: set[frozenset[Cell]],
    block: frozenset[Cell] = frozenset(),
) -> None:
    """A recursive backtracker from the last cell of ``stack``: a passage to a random unseen
    neighbour, and on from there; back when there is none. Entering a cell of ``block`` opens it
    once: the whole block counts as seen, and the carving goes on from the cell it came from."""
    while stack:
        here = stack[-1]
        options = _unseen_neighbours(here, cols, rows, seen)
        if not options:
            stack.pop()
            continue
        nxt = rng.choice(options)
        passages.add(frozenset({here, nxt}))
        if nxt in block:
            seen |= block
        else:
            seen.add(nxt)
            stack.append(nxt)


def _unseen_neighbours(cell: Cell, cols: int, rows: int, seen: set[Cell]) -> list[Cell]:
    """The cells beside ``cell`` on the grid that are not in ``seen``, in :data:`_STEPS` order."""
    c, r = cell
    near = [(c + dc, r + dr) for dc, dr in _STEPS]
    return [(x, y) for x, y in near if 0 <= x < cols and 0 <= y < rows and (x, y) not in seen]


def perfect_maze(
    cols: int,
    rows: int,
    seed: int,
    cell: float = 0.2,
    thickness: float = 0.01,
    start: Cell = (0, 0),
    exit_cell: Cell | None = None,
) -> Maze:
    """A random perfect maze with one exit gap in the top wall (above ``exit_cell``)."""
    rng = random.Random(seed)
    passages: set[frozenset[Cell]] = set()
    _carve(rng, cols, rows, [start], {start}, passages)
    exit_cell = exit_cell or (rng.randrange(cols), rows - 1)
    gap = frozenset({exit_cell, (exit_cell[0], rows)})
    walls = _walls_from_open(cols, rows, passages, cell, thickness, gaps={gap})
    heading = next(
        math.atan2(dr, dc) for dc, dr in _STEPS if frozenset({start, (start[0] + dc, start[1] + dr)}) in passages
    )
    spawn = Spawn(x=(start[0] + 0.5) * cell, y=(start[1] + 0.5) * cell, yaw=heading)
    return Maze(
        name=f"perfect_{cols}x{rows}_seed{seed}",
        walls=walls,
        spawns={"start": spawn},
        description=f"random perfect maze, exit above cell {exit_cell}",
    )


def random_path(length: int, seed: int, cols: int = 8, rows: int = 8) -> list[Cell]:
    """A random self-avoiding path of ``length`` cells on a grid (retries until one fits)."""
    rng = random.Random(seed)
    for _ in range(1000):
        path = [(rng.randrange(cols), rng.randrange(rows))]
        while len(path) < length:
            c, r = path[-1]
            options = [
                (c + dc, r + dr)
                for dc, dr in _STEPS
                if 0 <= c + dc < cols
                and 0 <= r + dr < rows
                and (c + dc, r + dr) not in path
                # never touch the path sideways: the corridor must have walls on both sides
                and sum((c + dc + a, r + dr + b) in path for a, b in _STEPS) == 1
            ]
            if not options:
                break
            path.append(rng.choice(options))
        if len(path) == length:
            return path
    raise ValueError(f"no self-avoiding path of {length} cells found on {cols}x{rows}")


def path_maze(path: list[Cell], cell: float = 0.2, thickness: float = 0.01) -> Maze:
    """A corridor along ``path`` (closed at both ends); spawn ``start`` in the first cell facing the second."""
    passages = {frozenset({a, b}) for a, b in pairwise(path)}
    cols = max(c for c, _ in path) + 1
    rows = max(r for _, r in path) + 1
    walls = _walls_from_open(cols, rows, passages, cell, thickness, inside=set(path))
    (c0, r0), (c1, r1) = path[0], path[1]
    spawn = Spawn(x=(c0 + 0.5) * cell, y=(r0 + 0.5) * cell, yaw=_STEPS[(c1 - c0, r1 - r0)])
    return Maze(name="path", walls=walls, spawns={"start": spawn}, description=f"corridor of {len(path)} cells")


def turns_along(path: list[Cell]) -> str:
    """The turns (L/R) a robot driving along ``path`` makes, e.g. 'RRL'."""
    out = []
    for a, b, c in zip(path, path[1:], path[2:], strict=False):  # each cell with the next two
        d1 = (b[0] - a[0], b[1] - a[1])
        d2 = (c[0] - b[0], c[1] - b[1])
        cross = d1[0] * d2[1] - d1[1] * d2[0]
        if cross:
            out.append("L" if cross > 0 else "R")
    return "".join(out)


def mirrored(maze: Maze, axis_x: float) -> Maze:
    """The maze mirrored about the vertical line x = ``axis_x`` (left turns become right turns)."""
    walls = [
        Wall(
            start=(round(2 * axis_x - w.start[0], 9), w.start[1]),
            end=(round(2 * axis_x - w.end[0], 9), w.end[1]),
            thickness=w.thickness,
            name=w.name,
        )
        for w in maze.walls
    ]
    spawns = {
        k: Spawn(
            x=round(2 * axis_x - s.x, 9),
            y=s.y,
            # not wrap_angle: a spawn's yaw is a start as written (mission/pass_base.py: exact, pi kept)
            yaw=math.remainder(math.pi - s.yaw, math.tau),
        )
        for k, s in maze.spawns.items()
    }
    return Maze(name=f"{maze.name}_mirrored", walls=walls, spawns=spawns, description=f"{maze.name} mirrored")


def _goal_block(size: int) -> tuple[frozenset[Cell], set[frozenset[Cell]]]:
    """The 2 x 2 goal block at the centre of a ``size`` maze, and the passages that open it inside."""
    half = size // 2
    sw, se, nw, ne = (half - 1, half - 1), (half, half - 1), (half - 1, half), (half, half)
    inside = {frozenset(pair) for pair in ((sw, se), (nw, ne), (sw, nw), (se, ne))}
    return frozenset({sw, se, nw, ne}), inside


def _inner_edges(size: int) -> list[frozenset[Cell]]:
    """Every pair of neighbouring cells of a ``size`` maze, column by column, row by row, east then north."""
    return [
        frozenset({(c, r), (c + dc, r + dr)})
        for c in range(size)
        for r in range(size)
        for dc, dr in ((1, 0), (0, 1))
        if c + dc < size and r + dr < size
    ]


def _closed_edges(size: int, passages: set[frozenset[Cell]]) -> tuple[set[Cell], set[Cell]]:
    """The cell edges that are walls, as :class:`~.micromouse.CellWalls` holds them: each (c, r) of
    ``horizontal`` the lower edge of cell (c, r), of ``vertical`` its left edge; the boundary closed."""
    horizontal = {
        (c, r)
        for c in range(size)
        for r in range(size + 1)
        if r in (0, size) or frozenset({(c, r - 1), (c, r)}) not in passages
    }
    vertical = {
        (c, r)
        for c in range(size + 1)
        for r in range(size)
        if c in (0, size) or frozenset({(c - 1, r), (c, r)}) not in passages
    }
    return horizontal, vertical


def contest_maze(seed: int, size: int = 16, loops: float = 0.1) -> CellWalls:
    """A maze of the micromouse contest kind, as cells and walls (:mod:`.micromouse` makes the geometry).

    The start is the bottom-left cell, open only to the north; the goal is the 2 x 2 block at the
    centre, open inside, with one entrance; the rest is a random perfect maze (recursive
    backtracker) in which a fraction ``loops`` of the inner walls is then removed, so that wall
    following is defeated by loops and a map and a plan are needed.
    """
    from thymio_bt.maze.micromouse import CellWalls

    rng = random.Random(seed)
    goal, passages = _goal_block(size)
    start = (0, 0)
    passages.add(frozenset({start, (0, 1)}))
    _carve(rng, size, size, [(0, 1)], {start, (0, 1)}, passages, goal)
    walls = [pair for pair in _inner_edges(size) if pair not in passages and not (pair & goal) and start not in pair]
    passages.update(rng.sample(walls, int(len(walls) * loops)))  # the loops
    horizontal, vertical = _closed_edges(size, passages)
    return CellWalls(size, size, frozenset(horizontal), frozenset(vertical), start, frozenset(goal))
