"""Mazes: walls as segments with a thickness, named spawn poses, and ways to make them."""

from thymio_bt.maze.files import load_maze, resolve_maze
from thymio_bt.maze.grid import maze_from_grid
from thymio_bt.maze.model import Maze, Obstacle, Spawn, Wall

__all__ = ["Maze", "Obstacle", "Spawn", "Wall", "load_maze", "resolve_maze", "maze_from_grid"]
