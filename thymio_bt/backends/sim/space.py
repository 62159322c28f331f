"""The physics space a :class:`~thymio_bt.backends.sim.world.Simulation` steps, built once per
simulation: the maze's walls and obstacles as static shapes with a clearance tracker over them, and
each robot entity's bodies and joints (:class:`RobotBody`).

Physics, in metres:

- walls are static boxes (``Wall.corners``), the robot a dynamic convex hull (``RobotModel.hull``)
  whose centre of gravity sits on the wheel axle, so spinning keeps the axle fixed;
- the robot is pulled by a kinematic control body through a pivot joint at the axle and a gear
  joint (pymunk's top-down "tank" recipe): it follows (v, ω) exactly in free space, while walls
  push back instead of being tunnelled (a kinematic robot, or a dynamic one whose velocity is
  overwritten every step, goes through walls);
- ``collision_slop`` is 0.2 mm (pymunk's default 0.1 would be 10 cm in metres).

Example::

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> from thymio_bt.robot.model import COURSE
    >>> built = MazeSpace(load_maze(resolve_maze("two_parts_maze")), COURSE)
    >>> len(built.space.shapes), built.bounds == built.shapes.bounds
    (21, True)
    >>> robot = RobotBody(built.space, Pose(0.1, 0.1, 0.0), group=1, model=COURSE)
    >>> robot.pose()
    Pose(x=0.1, y=0.1, yaw=0.0)
"""

from __future__ import annotations

import pymunk

from thymio_bt.backends.sim.clearance import ClearanceTracker
from thymio_bt.backends.sim.fastpath import NearShapes, body_driver, body_reader, control_aimer, spinner
from thymio_bt.geometry import Pose, new_pose, wrap_angle
from thymio_bt.maze import Maze
from thymio_bt.robot.model import RobotModel
from thymio_bt.robot.placement import MazeShapes

#: collision types: a robot's hull touching a wall is a collision
ROBOT_TYPE, WALL_TYPE = 1, 2
#: shape categories: readings cast when read see walls (and obstacles) only
WALLS, ROBOTS = 0b01, 0b10


def pose_of(x: float, y: float, angle: float) -> Pose:
    """A body's pose, its angle wrapped to [-pi, pi)."""
    return new_pose(x, y, wrap_angle(angle))


class MazeSpace:
    """A pymunk space holding ``maze``'s walls and obstacles (obstacles first) as static shapes, and a
    clearance tracker for ``model``'s hull over them."""

    def __init__(self, maze: Maze, model: RobotModel) -> None:
        self.space = pymunk.Space()
        self.space.collision_slop = 0.0002
        self.space.iterations = 10
        self.shapes = MazeShapes.of(maze)  # walls, then obstacles: polygons and boxes
        tracked = []
        walled = len(maze.walls)
        for index in (*range(walled, len(self.shapes.polygons)), *range(walled)):  # obstacles first
            corners = self.shapes.polygons[index]
            shape = pymunk.Poly(self.space.static_body, corners)
            shape.collision_type = WALL_TYPE
            shape.filter = pymunk.ShapeFilter(categories=WALLS)
            shape.friction = 1.0
            self.space.add(shape)
            tracked.append((shape, maze.walls[index] if index < walled else None, corners, self.shapes.boxes[index]))
        self.bounds = self.shapes.bounds
        self.clearance = ClearanceTracker(model, tracked, self.bounds)


class RobotBody:
    """One robot entity in the space: the hull body, its control body and joints, and the hot path's
    functions that read and drive them (:mod:`.fastpath`)."""

    def __init__(self, space: pymunk.Space, pose: Pose, group: int, model: RobotModel) -> None:
        self.body = pymunk.Body(model.mass, pymunk.moment_for_poly(model.mass, model.hull))
        self.body.center_of_gravity = (model.axle_x, 0.0)
        self.shape = pymunk.Poly(self.body, model.hull)
        self.shape.friction = 0.1  # the skid's mu in the URDF
        self.shape.collision_type = ROBOT_TYPE
        self.filter = pymunk.ShapeFilter(group=group)  # rays and queries skip the robot's own shape
        self.shape.filter = pymunk.ShapeFilter(group=group, categories=ROBOTS)
        self.control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        pivot = pymunk.PivotJoint(self.control, self.body, (0.0, 0.0), (model.axle_x, 0.0))
        pivot.max_bias = 0.0  # a pure velocity constraint: drift is not corrected
        pivot.max_force = 10.0  # traction: walls win against the wheels
        gear = pymunk.GearJoint(self.control, self.body, 0.0, 1.0)
        gear.max_bias = 0.0
        gear.max_force = 0.1
        self.joints = (pivot, gear)
        self.near = NearShapes(space, self.body, model.hull, self.filter)  # for the clearance tracker
        self.body.angle = pose.yaw
        self.body.position = (pose.x, pose.y)
        self.control.position = self.body.local_to_world((model.axle_x, 0.0))
        self.control.angle = pose.yaw
        space.add(self.body, self.shape, self.control, *self.joints)
        self.read = body_reader(self.body)  # (x, y, angle), the hot path's way to read the body
        self.aim = control_aimer(self.body, self.control)
        self.spin = spinner(self.control)
        self.drive = body_driver(self.body, self.control)

    def remove(self, space: pymunk.Space) -> None:
        """Take the entity's bodies, shape and joints out of ``space``."""
        space.remove(self.body, self.shape, self.control, *self.joints)

    def pose(self) -> Pose:
        """The hull body's pose now."""
        return pose_of(*self.read())
