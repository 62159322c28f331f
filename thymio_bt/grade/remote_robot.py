"""The robot as a submission's confined process sees it: a :class:`Robot` and :class:`Entities`
whose readings, odometry and clock arrive once a tick from the grader (:meth:`RemoteRobot.observe`)
and whose commands and entity requests go back with the tick's reply (:meth:`RemoteRobot.outbox`),
as a real robot's controller talks to its robot. The simulation and its ground truth stay with the
grader: nothing here can move the robot but a command.

The observation (grader to submission) is a binary frame (:data:`~.wire.OBSERVATION`: the clock,
whether the robot exists, odometry, the 7 proximity ranges, measured velocity, the command held,
collisions so far) with the entity requests served since the last tick as ``[id, "succeeded" |
"failed", reason]``. The reply (submission to grader, :func:`~.wire.reply_frame`): the root's
status, the drive commands given this tick (each ``[linear, angular]``), and, when there are any,
``q`` new entity requests ``[id, "delete" | "spawn", entity, x, y, yaw]``, ``ev`` the events the
tree emitted this tick, ``tip`` the running node's path when it changed, ``f`` ``[path, code,
reason]`` of a failure, ``x`` why the tick raised; while a tick takes long, ``{"slow": path}`` (JSON)
says which node it is in.

Example::

    >>> from thymio_bt.robot.model import robot_model
    >>> inf = float("inf")
    >>> robot = RemoteRobot(robot_model("course"))
    >>> robot.observe((0.1, True, True, True, 0.1, 0.2, 0.0, 0.05, *[inf] * 6, 0.0, 0.0, 0.0, 0.0, 0), [])
    >>> robot.time(), robot.pose().x, robot.proximity()["front_left"], robot.proximity()["rear_right"]
    (0.1, 0.1, 0.05, inf)
    >>> request = robot.request_delete("thymio"); robot.drive(0.1, 0.0)
    >>> robot.outbox()
    ([(0.1, 0.0)], [[0, 'delete', 'thymio', 0.0, 0.0, 0.0]])
    >>> robot.observe((0.2, False, False, False, *[0.0] * 3, *[inf] * 7, *[0.0] * 4, 0), [[0, "succeeded", None]])
    >>> request.state.name, robot.exists(), robot.pose()
    ('SUCCEEDED', False, None)
"""

from __future__ import annotations

from typing import Any

from thymio_bt.geometry import Pose
from thymio_bt.robot.interface import SENSOR_NAMES, Entities, Request, RequestState, Robot, Scan, Twist
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
        self._drives: list[tuple[float, float]] = []

    def observe(self, values: tuple[Any, ...], served: list[list[Any]]) -> None:
        """Take in one tick's observation: the fields of :data:`~.wire.OBSERVATION` after its tag,
        and the entity requests served."""
        self._time, self._exists, has_pose, has_scan = values[:4]
        self._pose = Pose(*values[4:7]) if has_pose else None
        self._scan = dict(zip(SENSOR_NAMES, values[7:14], strict=True)) if has_scan else None
        self._velocity = Twist(values[14], values[15])
        self._command = Twist(values[16], values[17])
        self.collisions = values[18]
        for key, state, reason in served:
            request = self._requests.pop(int(key), None)
            if request is not None:
                request.state = RequestState(state)
                request.reason = reason

    def observe_time(self, t: float) -> None:
        """Take in the clock alone (the run's end)."""
        self._time = float(t)

    def outbox(self) -> tuple[list[tuple[float, float]], list[list[Any]]]:
        """The commands given since the last reply, each (a simulation with noisy wheels draws their
        error anew with every command), and the requests made; both emptied."""
        drives, self._drives = self._drives, []
        new, self._new = self._new, []
        return drives, new

    def drive(self, linear: float, angular: float) -> None:
        """Hold a velocity command (sent with the tick's reply)."""
        self._command = Twist(float(linear), float(angular))
        self._drives.append((self._command.linear, self._command.angular))

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
