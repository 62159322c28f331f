"""Mazes: walls as segments with a thickness, named spawn poses, and ways to make them."""

from .model import Maze, Obstacle, Spawn, Wall, load_maze, resolve_maze
from .grid import maze_from_grid

__all__ = ["Maze", "Obstacle", "Spawn", "Wall", "load_maze", "resolve_maze", "maze_from_grid"]
