"""The clearance tracker's wall grid never leaves out a wall near the query point."""

import random

import pymunk

from thymio_bt.maze import load_maze
from thymio_bt.sim.walls import wall_grid


def test_the_grid_serves_every_wall_a_space_point_query_finds():
    maze = load_maze("mazes/maze_6x6.yaml")
    space = pymunk.Space()
    shapes = []
    for wall in maze.walls:
        shapes.append(pymunk.Poly(space.static_body, wall.corners()))
        space.add(shapes[-1])
    boxes = tuple((min(x for x, _ in c), min(y for _, y in c), max(x for x, _ in c), max(y for _, y in c))
                  for c in (w.corners() for w in maze.walls))
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
    from thymio_bt.placement import MazeShapes, placement_problem
    from thymio_bt.robot import Pose
    from thymio_bt.robot_model import COURSE

    maze = load_maze("mazes/two_parts_maze.yaml")
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
