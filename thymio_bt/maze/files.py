"""Maze files in every form: the wall-list YAML, the grid (ASCII art) YAML, found by path or by name.

This is the only place that knows the file forms: :mod:`.model` is the maze itself, :mod:`.grid`
turns ASCII art into walls.

Example::

    >>> path = resolve_maze("two_parts_maze")          # ./mazes first, then the shipped ones
    >>> maze = load_maze(path)
    >>> path.name, len(maze.walls), sorted(maze.spawns)
    ('two_parts_maze.yaml', 21, ['bonus', 'part1', 'part2'])
    >>> resolve_maze("two_part_maze")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: maze not found: 'two_part_maze' (hint: ... did you mean 'two_parts_maze'?)
"""

from __future__ import annotations

import os
from pathlib import Path

from thymio_bt.data import MAZES
from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.validation import validate
from thymio_bt.inputs.yamlio import MarkedDict, load_yaml, mark_of
from thymio_bt.maze.model import Maze


def maze_dirs() -> list[Path]:
    """Where named mazes (``maze: two_parts_maze``) are looked up: ./mazes, then the shipped ones."""
    dirs = [Path.cwd() / "mazes", MAZES]
    return [d for i, d in enumerate(dirs) if d.is_dir() and d not in dirs[:i]]


def load_maze(path: str | Path) -> Maze:
    """Load a maze file (YAML, the grid form with a ``grid:`` key, or a micromouse ``.txt``);
    errors give file:line."""
    if Path(path).suffix.lower() == ".txt":
        from thymio_bt.maze.micromouse import read_micromouse

        return read_micromouse(path)
    data = load_yaml(path, "maze")
    if not isinstance(data, MarkedDict):
        line, col = mark_of(data, (1, 1))
        raise UserError(
            Problem(
                "a maze file must be a mapping with 'walls:' (or 'grid:')",
                str(path),
                line,
                col,
                hint="see mazes/two_parts_maze.yaml (walls) or mazes/arena.yaml (grid)",
            )
        )
    if "grid" in data:
        from thymio_bt.maze.grid import GridMazeFile, maze_from_grid_file  # a maze of walls needs neither

        header = validate(GridMazeFile, data, str(path))  # units and types, before the art is read
        return maze_from_grid_file(header, data.value_marks["grid"], str(path))
    return validate(Maze, data, str(path))


def maze_reference(path: str | Path, folder: Path | None = None) -> str:
    """How an output (an export, a hint) names the maze file ``path``: a shipped maze by its name,
    which finds it wherever thymio-bt is installed; another by its path, relative to ``folder`` (the
    output's) when given.

    >>> maze_reference(MAZES / "two_parts_maze.yaml", Path("/somewhere/else"))
    'two_parts_maze'
    >>> maze_reference("/home/ada/my_maze.yaml", Path("/home/ada/out"))
    '../my_maze.yaml'
    """
    resolved = Path(path).resolve()
    if resolved.parent == MAZES.resolve():
        try:
            if resolve_maze(resolved.stem).resolve() == resolved:  # not hidden by a ./mazes of that name
                return resolved.stem
        except UserError:
            pass
    return os.path.relpath(path, folder) if folder is not None else os.path.normpath(path)


def resolve_maze(ref: str, relative_to: Path | None = None, owner: str = "the mission file") -> Path:
    """Find a maze by path (relative to ``relative_to``, the folder of ``owner``) or by name in the
    project's mazes/."""
    candidates = []
    ref_path = Path(ref)
    if relative_to is not None and not ref_path.is_absolute():
        candidates.append(relative_to / ref_path)
    candidates.append(ref_path)
    if ref_path.suffix == "" and len(ref_path.parts) == 1:
        candidates += [d / f"{ref}{suffix}" for d in maze_dirs() for suffix in (".yaml", ".txt")]
    for candidate in candidates:
        if candidate.exists():  # a folder or a FIFO too: reading it says what is wrong
            return candidate
    known = sorted({p.stem for d in maze_dirs() for p in (*d.glob("*.yaml"), *d.glob("*.txt"))})
    raise UserError(
        Problem(
            f"maze not found: '{ref}'",
            hint=(
                f"a path relative to {owner}, or a named maze: "
                + (did_you_mean(ref, known) if known else "none installed")
            ),
        )
    )
