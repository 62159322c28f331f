"""Mazes: walls as segments with a thickness, named spawn poses, and ways to make them."""

from .files import load_maze, resolve_maze
from .grid import maze_from_grid
from .model import Maze, Obstacle, Spawn, Wall

__all__ = ["Maze", "Obstacle", "Spawn", "Wall", "load_maze", "resolve_maze", "maze_from_grid"]
