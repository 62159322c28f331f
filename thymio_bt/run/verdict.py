"""The verdict on a run: which of its mission's ``expect:`` criteria (:mod:`thymio_bt.plan.expect`)
it does not meet, judged on the run's ground truth after it ends.

A run whose tree succeeds but whose expectations do not all hold ends FAILURE with code
``EXPECTATION`` and the failed ones in its reason; ``sweep`` counts it as a failure. The grader
judges a stop with the same words (:func:`stop_problem`).

Example::

    >>> from types import SimpleNamespace
    >>> from thymio_bt.mission.loader import load_mission
    >>> from thymio_bt.robot.model import robot_model
    >>> mission, model = load_mission("maze_part1_2"), robot_model("course")
    >>> round(front_gap(mission.maze, model, mission.start), 4)        # at the start: 44 cm to the wall
    0.4393
    >>> run = SimpleNamespace(final_pose=Pose(0.3, 0.5, 0.0), collisions=1, sim_time=42.0,
    ...                       events=[], trajectory=[])                 # a RunResult's fields
    >>> for failed in check(mission.expect, run, mission.maze, model):  # [] when all hold
    ...     print(failed)
    goal: ended 11.0 mm from (0.3, 0.489), more than 10 mm
    no_collision: 1 collision
    gaps: no node matching 'course/part 1' ended with a robot
"""

from __future__ import annotations

import math
from bisect import bisect_right
from fnmatch import fnmatchcase
from operator import itemgetter
from typing import TYPE_CHECKING

from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze
from thymio_bt.plan.expect import DeadEnd, Expect
from thymio_bt.robot.model import RobotModel
from thymio_bt.robot.placement import ray_distance

if TYPE_CHECKING:
    from thymio_bt.run.result import RunResult

__all__ = ["check", "front_gap", "open_side", "stop_problem"]


def check(expect: Expect, result: RunResult, maze: Maze, model: RobotModel) -> list[str]:
    """The expectations ``result`` does not meet."""
    failed = []
    pose: Pose | None = result.final_pose
    if expect.goal is not None:
        if pose is None:
            failed.append("goal: no robot at the end")
        else:
            off = math.dist((pose.x, pose.y), expect.goal.centre)
            if off > expect.goal.radius:
                failed.append(
                    f"goal: ended {1000 * off:.1f} mm from ({expect.goal.centre[0]:g}, "
                    f"{expect.goal.centre[1]:g}), more than {1000 * expect.goal.radius:g} mm"
                )
    if expect.leaves_maze:
        if pose is None:
            failed.append("leaves_maze: no robot at the end")
        elif not maze.outside(pose.x, pose.y):
            failed.append(f"leaves_maze: ended inside the maze at ({pose.x:.2f}, {pose.y:.2f})")
    if expect.dead_end is not None:
        failed += _dead_end(expect.dead_end, pose, maze, model)
    if expect.no_collision and result.collisions:
        failed.append(f"no_collision: {result.collisions} collision{'s' * (result.collisions != 1)}")
    if expect.max_time is not None and result.sim_time > expect.max_time + 1e-9:
        failed.append(f"max_time: took {result.sim_time:.1f} s, more than {expect.max_time:g} s")
    for gap in expect.gaps:
        ended = next(
            (
                e
                for e in result.events
                if e["kind"] == "behaviour_end" and e.get("pose") and fnmatchcase(e["path"], gap.after)
            ),
            None,
        )
        if ended is None:
            failed.append(f"gaps: no node matching '{gap.after}' ended with a robot")
            continue
        measured = front_gap(maze, model, _true_pose_at(result, ended))
        if abs(measured - gap.distance) > gap.tolerance:
            failed.append(
                f"gaps: after '{ended['path']}' the front gap was {100 * measured:.2f} cm, "
                f"not {100 * gap.distance:g} ± {100 * gap.tolerance:g} cm"
            )
    return failed


def _true_pose_at(result: RunResult, event: dict) -> Pose:
    """Where the robot really was when ``event`` happened: the trajectory's true pose of that tick
    (an event's own pose is the robot's odometry, which drifts on a real or late robot). The
    trajectory's times ascend."""
    before = bisect_right(result.trajectory, event["t"] + 1e-9, key=itemgetter(0))
    if not before:
        return Pose(event["pose"]["x"], event["pose"]["y"], event["pose"]["yaw"])
    return Pose(*result.trajectory[before - 1][1:4])


def _dead_end(spec: DeadEnd, pose: Pose | None, maze: Maze, model: RobotModel) -> list[str]:
    """Why the final ``pose`` (the true one) is not in a dead end as ``spec`` says, if it is not."""
    if pose is None:
        return ["dead_end: no robot at the end"]
    problem = stop_problem(maze, model, pose, spec.distance, spec.tolerance, spec.side)
    return [] if problem is None else [f"dead_end: {problem}"]


def stop_problem(
    maze: Maze, model: RobotModel, pose: Pose, distance: float, tolerance: float, side: float | None = None
) -> str | None:
    """Why a robot at ``pose`` (its true pose) has not stopped ``distance`` ± ``tolerance`` from the
    wall ahead, or, given ``side``, not in a dead end (a wall within ``side`` on both sides); None
    when it has. The one judgement of a stop for ``expect:`` and the grader, in the same words.

    >>> from thymio_bt.mission.loader import load_mission
    >>> from thymio_bt.robot.model import robot_model
    >>> mission, model = load_mission("maze_part1_2"), robot_model("course")
    >>> stop_problem(mission.maze, model, mission.start, 0.05, 0.005)  # not moved yet
    'stopped 43.9 cm from the wall, wanted 5.0 +- 0.5 cm'
    """
    gap = front_gap(maze, model, pose)
    if math.isinf(gap):
        return f"stopped facing no wall (wanted {100 * distance:g} cm from one)"
    if abs(gap - distance) > tolerance:
        return f"stopped {100 * gap:.1f} cm from the wall, wanted {100 * distance:.1f} +- {100 * tolerance:.1f} cm"
    opening = None if side is None else open_side(maze, pose, side)
    return None if opening is None else f"stopped where the {opening} side is open: not a dead end"


def open_side(maze: Maze, pose: Pose, reach: float) -> str | None:
    """``left`` or ``right``, the first side of ``pose`` with no wall within ``reach`` of base_link
    (square to the heading), or None: both sides closed."""
    for name, turn in (("left", math.pi / 2), ("right", -math.pi / 2)):
        if ray_distance(maze, pose.x, pose.y, pose.yaw + turn) > reach:
            return name
    return None


def front_gap(maze: Maze, model: RobotModel, pose: Pose) -> float:
    """The distance from the robot's nose (the front of its hull on its centre line) straight ahead
    to the nearest wall or obstacle; inf when nothing is ahead."""
    nose = max(x for x, _ in model.hull)
    return ray_distance(maze, pose.x + nose * math.cos(pose.yaw), pose.y + nose * math.sin(pose.yaw), pose.yaw)
