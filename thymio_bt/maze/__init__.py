"""Mazes: walls as segments with a thickness, named spawn poses, and ways to make them.

``maze_from_grid`` (:mod:`.grid`) loads on first use: a maze of walls, as most missions have, needs
none of the grid's code or models.
"""

from typing import TYPE_CHECKING, Any

from thymio_bt.maze.files import load_maze, resolve_maze
from thymio_bt.maze.model import Maze, Obstacle, Spawn, Wall

if TYPE_CHECKING:
    from thymio_bt.maze.grid import maze_from_grid

__all__ = ["Maze", "Obstacle", "Spawn", "Wall", "load_maze", "resolve_maze", "maze_from_grid"]


def __getattr__(name: str) -> Any:
    """``maze_from_grid``, from :mod:`.grid` on first use (PEP 562)."""
    if name == "maze_from_grid":
        from thymio_bt.maze.grid import maze_from_grid

        return maze_from_grid
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
