"""What keeps behaviours right on a late or glinting robot (the Playground, a real Thymio): a single
near reading right after nothing was in range does not stop MoveUntilWall, approach gains are capped
by the robot's latency, and the expected front gaps are measured on the true pose, not odometry."""

import math
from types import SimpleNamespace

import pytest

from thymio_bt.behaviours import Context, MoveUntilWall
from thymio_bt.behaviours.motion import DAMPED_GAIN_DELAY, late_gain
from thymio_bt.behaviours.ticking import tick
from thymio_bt.expect import Expect, check
from thymio_bt.maze import load_maze
from thymio_bt.robot import SENSOR_NAMES, Pose
from thymio_bt.robot_model import COURSE
from py_trees.common import Status


class ScriptedRobot:
    """A robot driving along +x at its last command, whose front-centre sensor reads a script."""

    latency = 0.0

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
    assert statuses == [Status.RUNNING] * 5          # held still for the glint's tick, then on its way
    assert robot.v == pytest.approx(0.1)


def test_a_wall_that_stays_near_stops_it_a_tick_later():
    robot = ScriptedRobot([math.inf, 0.04, 0.04])
    node = MoveUntilWall("approach", MoveUntilWall.Params(distance=0.05), Context(robot=robot, entities=robot))
    tick(node)
    robot.advance()
    tick(node)                                       # 4 cm right after nothing: checked, robot held
    assert node.status == Status.RUNNING and robot.v == 0.0
    robot.advance()
    tick(node)
    assert node.status == Status.SUCCESS


def test_approach_gains_are_capped_by_latency_only_on_late_robots():
    assert late_gain(5.0, SimpleNamespace(latency=0.0), 0.1) == 5.0
    assert late_gain(5.0, SimpleNamespace(), 0.1) == 5.0
    assert late_gain(5.0, SimpleNamespace(latency=0.2), 0.1) == pytest.approx(DAMPED_GAIN_DELAY / 0.3)
    assert late_gain(1.0, SimpleNamespace(latency=0.2), 0.1) == 1.0


def test_expected_gaps_are_measured_on_the_true_pose_not_odometry():
    maze = load_maze("mazes/two_parts_maze.yaml")
    truth = 0.595 - 0.05 - max(x for x, _ in COURSE.hull)          # base_link 5 cm from part 1's wall
    event = {"t": 4.0, "kind": "behaviour_end", "path": "course/part 1",
             "pose": {"x": truth + 0.013, "y": 0.1, "yaw": 0.0}}     # odometry 1.3 cm too far
    result = SimpleNamespace(final_pose={"x": truth, "y": 0.1, "yaw": 0.0}, collisions=0, sim_time=5.0,
                             events=[event], trajectory=[(3.9, truth - 0.001, 0.1, 0.0), (4.0, truth, 0.1, 0.0),
                                                         (4.1, truth, 0.1, 0.0)])
    expect = Expect.model_validate({"gaps": [{"after": "course/part 1", "distance": 0.05, "tolerance": 0.001}]})
    assert check(expect, result, maze, COURSE) == []


def test_wall_follow_is_not_out_of_the_maze_while_a_wall_is_in_front():
    """Odometry that drifted past the maze's box does not end WallFollow while a wall is still seen."""
    from thymio_bt.behaviours import WallFollow

    robot = ScriptedRobot([0.05, 0.05, math.inf])
    robot.x = 1.2                                           # beyond the box by odometry
    ctx = Context(robot=robot, entities=robot, bounds=(0.0, 0.0, 1.0, 1.0))
    node = WallFollow("follow", WallFollow.Params(), ctx)
    tick(node)
    assert node.status == Status.RUNNING                    # a wall ahead: still inside
    robot.advance()
    robot.advance()
    tick(node)
    assert node.status == Status.SUCCESS                    # nothing in front any more: out


def test_wall_follow_retakes_the_corridor_heading_from_a_steady_offset():
    """Between two walls, an offset that holds still means the robot is parallel to the corridor:
    WallFollow takes its odometry heading then as the corridor's (drift corrected), not before."""
    from thymio_bt.behaviours import WallFollow

    class Corridor(ScriptedRobot):
        yaw = 0.0

        def proximity(self):
            scan = dict.fromkeys(SENSOR_NAMES, math.inf)
            scan["front_left"] = scan["front_right"] = 0.074      # centred: offset 0
            return scan

        def pose(self):
            return Pose(self.x, 0.1, self.yaw)

    robot = Corridor([])
    node = WallFollow("follow", WallFollow.Params(), Context(robot=robot, entities=robot, bounds=(0, 0, 5, 1)))
    tick(node)
    robot.yaw = math.radians(3)                 # odometry now says 3° off while the walls say parallel
    for _ in range(3):
        tick(node)
    assert node.heading == 0.0                  # not steady for long enough yet
    for _ in range(2):
        tick(node)
    assert node.heading == pytest.approx(math.radians(3))
