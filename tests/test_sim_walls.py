"""The clearance tracker's wall grid never leaves out a wall near the query point."""

import random
from pathlib import Path

import pymunk

from thymio_bt.backends.sim.walls import wall_grid
from thymio_bt.maze import load_maze

ROOT = Path(__file__).resolve().parents[1]


def test_the_grid_serves_every_wall_a_space_point_query_finds():
    maze = load_maze(f"{ROOT}/mazes/maze_6x6.yaml")
    space = pymunk.Space()
    shapes = []
    for wall in maze.walls:
        shapes.append(pymunk.Poly(space.static_body, wall.corners()))
        space.add(shapes[-1])
    boxes = tuple(
        (min(x for x, _ in c), min(y for _, y in c), max(x for x, _ in c), max(y for _, y in c))
        for c in (w.corners() for w in maze.walls)
    )
    grid = wall_grid(boxes, 0.05, 0.13)
    xmin, ymin, xmax, ymax = maze.bounds()
    rng = random.Random(3)
    for _ in range(2000):
        x, y, radius = rng.uniform(xmin - 0.1, xmax + 0.1), rng.uniform(ymin - 0.1, ymax + 0.1), rng.uniform(0, 0.2)
        found = {shapes.index(hit.shape) for hit in space.point_query((x, y), radius, pymunk.ShapeFilter())}
        assert found <= set(grid.near(x, y, radius))


def test_placement_with_precomputed_shapes_gives_the_same_answers():
    """MazeShapes (the simulator's cached polygons, boxes skipped when far apart) answers as the maze does,
    also for poses that touch or nearly touch a wall."""
    from thymio_bt.robot.interface import Pose
    from thymio_bt.robot.model import COURSE
    from thymio_bt.robot.placement import MazeShapes, placement_problem

    maze = load_maze(f"{ROOT}/mazes/two_parts_maze.yaml")
    shapes = MazeShapes.of(maze)
    xmin, ymin, xmax, ymax = maze.bounds()
    rng = random.Random(5)
    answers = set()
    for _ in range(1500):
        pose = Pose(rng.uniform(xmin, xmax), rng.uniform(ymin, ymax), rng.uniform(-3.2, 3.2))
        answer = placement_problem(shapes, COURSE, pose)
        assert answer == placement_problem(maze, COURSE, pose)
        answers.add(answer is None)
    assert answers == {True, False}


def test_maze_shapes_are_the_mazes_corners_and_bounds_and_shared_only_bit_for_bit():
    """MazeShapes.of is cached by the walls' floats: it gives every maze's corners, boxes and bounds
    (obstacles too), and mazes that differ in one float, even a zero's sign, do not share it."""
    import glob

    from thymio_bt.maze import Maze, Wall
    from thymio_bt.robot.placement import MazeShapes

    for path in sorted(glob.glob(f"{ROOT}/mazes/*.yaml")):
        maze = load_maze(path)
        shapes = MazeShapes.of(maze)
        assert shapes.polygons == tuple(tuple(s.corners()) for s in (*maze.walls, *maze.obstacles)), path
        assert shapes.bounds == maze.bounds(), path
        assert MazeShapes.of(load_maze(path)) == shapes
    plus, minus = (Maze(walls=[Wall(start=(zero, 0.0), end=(0.0, 0.5))]) for zero in (0.0, -0.0))
    assert MazeShapes.of(plus) is MazeShapes.of(Maze(walls=[Wall(start=(0.0, 0.0), end=(0.0, 0.5))]))
    assert MazeShapes.of(plus) is not MazeShapes.of(minus)
    moved = Maze(walls=[Wall(start=(0.0, 0.0), end=(0.0, 0.5 + 1e-12))])
    assert MazeShapes.of(moved).bounds == moved.bounds() != plus.bounds()
