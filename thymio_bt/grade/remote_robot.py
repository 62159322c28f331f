"""The robot as a submission's confined process sees it: a :class:`Robot` and :class:`Entities`
whose readings, odometry and clock arrive once a tick from the grader (:meth:`RemoteRobot.observe`)
and whose commands and entity requests go back with the tick's reply (:meth:`RemoteRobot.outbox`),
as a real robot's controller talks to its robot. The simulation and its ground truth stay with the
grader: nothing here can move the robot but a command.

The observation (grader to submission) and the reply (submission to grader), JSON objects:

- observation: ``t`` clock (s), ``e`` whether the robot exists, ``p`` odometry ``[x, y, yaw]``
  or None, ``s`` the 7 proximity ranges (``SENSOR_NAMES`` order, None: nothing in range) or None,
  ``v`` measured ``[linear, angular]``, ``c`` the command held ``[linear, angular]``, ``n``
  collisions so far, ``r`` entity requests served since the last tick as
  ``[id, "succeeded" | "failed", reason]``;
- reply: ``st`` the root's status, ``d`` the drive commands given this tick (each
  ``[linear, angular]``), ``q`` new entity requests ``[id, "delete" | "spawn", entity, x, y,
  yaw]``, ``ev`` the events the tree emitted this tick, ``tip`` the running node's path when it
  changed, ``f`` ``[path, code, reason]`` of a failure, ``x`` why the tick raised; while a tick
  takes long, ``{"slow": path}`` says which node it is in.

Example::

    >>> from thymio_bt.robot.model import robot_model
    >>> robot = RemoteRobot(robot_model("course"))
    >>> robot.observe({"t": 0.1, "e": True, "p": [0.1, 0.2, 0.0], "s": [0.05] + [None] * 6,
    ...                "v": [0.0, 0.0], "c": [0.0, 0.0], "n": 0, "r": []})
    >>> robot.time(), robot.pose().x, robot.proximity()["front_left"], robot.proximity()["rear_right"]
    (0.1, 0.1, 0.05, inf)
    >>> request = robot.request_delete("thymio"); robot.drive(0.1, 0.0)
    >>> robot.outbox()
    ([[0.1, 0.0]], [[0, 'delete', 'thymio', 0.0, 0.0, 0.0]])
    >>> robot.observe({"t": 0.2, "e": False, "p": None, "s": None, "v": [0, 0], "c": [0, 0], "n": 0,
    ...                "r": [[0, "succeeded", None]]})
    >>> request.state.name, robot.exists(), robot.pose()
    ('SUCCEEDED', False, None)
"""

from __future__ import annotations

import math
from typing import Any

from thymio_bt.robot.interface import (
    SENSOR_NAMES,
    Entities,
    Pose,
    Request,
    RequestState,
    Robot,
    Scan,
    Twist,
)
from thymio_bt.robot.model import RobotModel


class RemoteRobot(Robot, Entities):
    """The grader's robot, known only by what it sends each tick."""

    def __init__(self, model: RobotModel) -> None:
        self.model = model
        self._time = 0.0
        self._exists = False
        self._pose: Pose | None = None
        self._scan: dict[str, float] | None = None
        self._velocity = Twist()
        self._command = Twist()
        self.collisions = 0
        self._requests: dict[int, Request] = {}
        self._new: list[list[Any]] = []
        self._next = 0
        self._drives: list[list[float]] = []

    def observe(self, message: dict[str, Any]) -> None:
        """Take in one tick's observation."""
        self._time = float(message["t"])
        self._exists = bool(message["e"])
        pose = message["p"]
        self._pose = None if pose is None else Pose(*map(float, pose))
        scan = message["s"]
        self._scan = (
            None
            if scan is None
            else {n: math.inf if r is None else float(r) for n, r in zip(SENSOR_NAMES, scan, strict=False)}
        )
        self._velocity = Twist(*map(float, message["v"]))
        self._command = Twist(*map(float, message["c"]))
        self.collisions = int(message["n"])
        for key, state, reason in message["r"]:
            request = self._requests.pop(int(key), None)
            if request is not None:
                request.state = RequestState(state)
                request.reason = reason

    def observe_time(self, t: float) -> None:
        """Take in the clock alone (the run's end)."""
        self._time = float(t)

    def outbox(self) -> tuple[list[list[float]], list[list[Any]]]:
        """The commands given since the last reply, each (a simulation with noisy wheels draws their
        error anew with every command), and the requests made; both emptied."""
        drives, self._drives = self._drives, []
        new, self._new = self._new, []
        return drives, new

    def drive(self, linear: float, angular: float) -> None:
        """Hold a velocity command (sent with the tick's reply)."""
        self._command = Twist(float(linear), float(angular))
        self._drives.append([self._command.linear, self._command.angular])

    def exists(self) -> bool:
        """Whether the robot exists, as last observed."""
        return self._exists

    def proximity(self) -> Scan | None:
        """The proximity ranges last observed (inf: nothing in range)."""
        return self._scan

    def pose(self) -> Pose | None:
        """The odometry pose last observed."""
        return self._pose

    def velocity(self) -> Twist:
        """The measured velocity last observed."""
        return self._velocity

    def command(self) -> Twist:
        """The command held."""
        return self._command

    def time(self) -> float:
        """The grader's clock, as last observed."""
        return self._time

    def request_delete(self, name: str) -> Request:
        """Ask the grader to remove an entity (answered in a later observation)."""
        return self._request(Request("delete", name))

    def request_spawn(self, name: str, pose: Pose) -> Request:
        """Ask the grader for a robot at ``pose`` (answered in a later observation)."""
        return self._request(Request("spawn", name, pose))

    def _request(self, request: Request) -> Request:
        key, self._next = self._next, self._next + 1
        self._requests[key] = request
        pose = request.pose or Pose(0.0, 0.0, 0.0)
        self._new.append([key, request.kind, request.entity, pose.x, pose.y, pose.yaw])
        return request
