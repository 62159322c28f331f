"""What keeps behaviours right on a late or glinting robot (the Playground, a real Thymio): a single
near reading right after nothing was in range does not stop MoveUntilWall, approach gains are capped
by the robot's latency, and the expected front gaps are measured on the true pose, not odometry."""

import math
from pathlib import Path
from types import SimpleNamespace

import pytest
from py_trees.common import Status

from thymio_bt.behaviours import Context, MoveUntilWall
from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.behaviours.motion import DAMPED_GAIN_DELAY, late_gain
from thymio_bt.maze import load_maze
from thymio_bt.plan.expect import Expect
from thymio_bt.robot.interface import SENSOR_NAMES, Pose
from thymio_bt.robot.model import COURSE
from thymio_bt.run.verdict import check

ROOT = Path(__file__).resolve().parents[1]


class ScriptedRobot:
    """A robot driving along +x at its last command, whose front-centre sensor reads a script."""

    latency = 0.0
    model = COURSE  # a Robot's model: behaviours read its sensor poses and axle there

    def __init__(self, readings):
        self.readings, self.i, self.x, self.v = list(readings), 0, 0.1, 0.0

    def advance(self):
        self.i += 1
        self.x += self.v * 0.1

    def proximity(self):
        scan = dict.fromkeys(SENSOR_NAMES, math.inf)
        scan["front_center"] = self.readings[min(self.i, len(self.readings) - 1)]
        return scan

    def pose(self):
        return Pose(self.x, 0.1, 0.0)

    def exists(self):
        return True

    def drive(self, v, w):
        self.v = v

    def time(self):
        return self.i * 0.1


def test_one_glint_right_after_nothing_does_not_stop_move_until_wall():
    robot = ScriptedRobot([math.inf, math.inf, 0.0, math.inf, math.inf])
    node = MoveUntilWall("approach", MoveUntilWall.Params(distance=0.05), Context(robot=robot, entities=robot))
    statuses = []
    for _ in range(5):
        tick(node)
        statuses.append(node.status)
        robot.advance()
    assert statuses == [Status.RUNNING] * 5  # held still for the glint's tick, then on its way
    assert robot.v == pytest.approx(0.1)


def test_a_wall_that_stays_near_stops_it_a_tick_later():
    robot = ScriptedRobot([math.inf, 0.04, 0.04])
    node = MoveUntilWall("approach", MoveUntilWall.Params(distance=0.05), Context(robot=robot, entities=robot))
    tick(node)
    robot.advance()
    tick(node)  # 4 cm right after nothing: checked, robot held
    assert node.status == Status.RUNNING and robot.v == 0.0
    robot.advance()
    tick(node)
    assert node.status == Status.SUCCESS


def test_approach_gains_are_capped_by_latency_only_on_late_robots():
    assert late_gain(5.0, 0.0, 0.1) == 5.0
    assert late_gain(5.0, 0.2, 0.1) == pytest.approx(DAMPED_GAIN_DELAY / 0.3)
    assert late_gain(1.0, 0.2, 0.1) == 1.0


def test_expected_gaps_are_measured_on_the_true_pose_not_odometry():
    maze = load_maze(f"{ROOT}/mazes/two_parts_maze.yaml")
    truth = 0.595 - 0.05 - max(x for x, _ in COURSE.hull)  # base_link 5 cm from part 1's wall
    event = {
        "t": 4.0,
        "kind": "behaviour_end",
        "path": "course/part 1",
        "pose": {"x": truth + 0.013, "y": 0.1, "yaw": 0.0},
    }  # odometry 1.3 cm too far
    result = SimpleNamespace(
        final_pose=Pose(truth, 0.1, 0.0),
        collisions=0,
        sim_time=5.0,
        events=[event],
        trajectory=[(3.9, truth - 0.001, 0.1, 0.0), (4.0, truth, 0.1, 0.0), (4.1, truth, 0.1, 0.0)],
    )
    expect = Expect.model_validate({"gaps": [{"after": "course/part 1", "distance": 0.05, "tolerance": 0.001}]})
    assert check(expect, result, maze, COURSE) == []


def test_wall_follow_is_not_out_of_the_maze_while_a_wall_is_in_front():
    """Odometry that drifted past the maze's box does not end WallFollow while a wall is still seen."""
    from thymio_bt.behaviours import WallFollow

    robot = ScriptedRobot([0.05, 0.05, math.inf])
    robot.x = 1.2  # beyond the box by odometry
    ctx = Context(robot=robot, entities=robot, bounds=(0.0, 0.0, 1.0, 1.0))
    node = WallFollow("follow", WallFollow.Params(), ctx)
    tick(node)
    assert node.status == Status.RUNNING  # a wall ahead: still inside
    robot.advance()
    robot.advance()
    tick(node)
    assert node.status == Status.SUCCESS  # nothing in front any more: out


class DriftingCorridor:
    """A robot in a straight corridor along +x (walls at y = ±0.095), turned by ``-bias`` from it
    while its odometry, turned by ``bias`` from the world (drift from earlier turns), says it is
    parallel to it; it reads the walls from its true pose."""

    latency = 0.0
    model = COURSE

    def __init__(self, bias):
        self.bias, self.x, self.y, self.yaw, self.v, self.w, self.t = bias, 0.1, 0.0, -bias, 0.0, 0.0, 0.0

    def advance(self):
        self.x += self.v * 0.1 * math.cos(self.yaw)
        self.y += self.v * 0.1 * math.sin(self.yaw)
        self.yaw += self.w * 0.1
        self.t += 0.1

    def pose(self):
        c, s = math.cos(self.bias), math.sin(self.bias)
        return Pose(c * self.x - s * self.y, s * self.x + c * self.y, self.yaw + self.bias)

    def proximity(self):
        scan = dict.fromkeys(SENSOR_NAMES, math.inf)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        for sensor in COURSE.sensors:
            sy = self.y + s * sensor.x + c * sensor.y
            direction = math.sin(self.yaw + sensor.yaw)
            for wall in (0.095, -0.095):
                if direction * (wall - sy) > 0:
                    reach = (wall - sy) / direction
                    if reach <= COURSE.range_max:
                        scan[sensor.name] = min(scan[sensor.name], reach)
        return scan

    def exists(self):
        return True

    def drive(self, v, w):
        self.v, self.w = v, w

    def time(self):
        return self.t


@pytest.mark.parametrize("bias_deg", [-6.0, 4.0])
def test_wall_follow_retakes_the_corridor_heading_from_the_side_walls(bias_deg):
    """Odometry turned by a few degrees (a late robot's turns): the line through where the side rays
    meet the walls is the corridor in odometry's frame; WallFollow takes it as its heading within
    the first 10 cm and drives parallel to the walls, near the centre line, from then on."""
    from thymio_bt.behaviours import WallFollow

    robot = DriftingCorridor(math.radians(bias_deg))
    node = WallFollow("follow", WallFollow.Params(), Context(robot=robot, entities=robot, bounds=(0, -1, 5, 1)))
    tick(node)
    assert node.heading == 0.0  # odometry's yaw at the start
    for _ in range(10):
        robot.advance()
        tick(node)
    assert node.heading == pytest.approx(math.radians(bias_deg), abs=math.radians(0.5))  # the walls, in odometry
    for _ in range(20):
        robot.advance()
        tick(node)
    assert abs(robot.yaw) < math.radians(1.0) and abs(robot.y) < 0.01


def test_wall_follow_holds_on_a_glint_after_a_far_reading_and_does_not_turn():
    """Enki's cones read 0 at a wall's end: a near reading right after a far one (more than a tick's
    travel nearer) holds WallFollow still for a tick instead of stopping it before a wall and turning."""
    from thymio_bt.behaviours import WallFollow

    robot = ScriptedRobot([0.10, 0.09, 0.015, 0.08, 0.07])
    node = WallFollow("follow", WallFollow.Params(), Context(robot=robot, entities=robot, bounds=(0, 0, 5, 1)))
    speeds = []
    for _ in range(5):
        tick(node)
        speeds.append(robot.v)
        robot.advance()
    assert node.turns == [] and node.mode == "forward"
    assert speeds[2] == 0.0 and speeds[3] > 0.0  # held for the glint's tick, then on its way


def test_wall_follow_takes_a_reading_of_zero_for_nothing():
    """Enki's cones read 0 m at a wall's end for seconds while the robot stands or turns; WallFollow
    never comes that close on purpose, so such a reading neither stops nor turns it."""
    from thymio_bt.behaviours import WallFollow

    robot = ScriptedRobot([0.0] * 5)
    node = WallFollow("follow", WallFollow.Params(), Context(robot=robot, entities=robot, bounds=(0, 0, 5, 1)))
    for _ in range(5):
        tick(node)
        assert robot.v > 0.0
        robot.advance()
    assert node.turns == [] and node.mode == "forward"
