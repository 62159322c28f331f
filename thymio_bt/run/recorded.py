"""A recorded run as a backend: a tree ticked against it reads what the robot read then.

:class:`RecordedRobot` serves a :class:`~thymio_bt.logs.recording.Recording` tick by tick: the
proximity readings, the odometry pose, the measured velocity, the clock, whether the robot existed
and the collisions of the logged run; the commands the tree gives are kept, never acted on. That is
exact as long as the tree commands what the recorded one did (the what-if replay,
:mod:`thymio_bt.run.whatif`, checks it every tick); from then on :meth:`RecordedRobot.go_live`
hands every call to a live backend (the simulator) put in the recorded state, so the run goes on.

Example (the first recorded tick of a run, as a tree would read it):

>>> from thymio_bt.logs.recording import Recorder
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> recorder = Recorder(statuses=True)
>>> recording = recorder.finish(Run(load_mission("square")).run(on_tick=recorder))
>>> robot = RecordedRobot(recording)
>>> robot.time(), robot.pose(), robot.exists()
(0.0, Pose(x=0.45, y=0.45, yaw=0.0), True)
>>> robot.advance(0.1)
>>> robot.time(), robot.velocity()
(0.1, Twist(linear=0.1, angular=0.0))
"""

from __future__ import annotations

import math
from typing import Any

from thymio_bt.geometry import Pose, new_pose, wrap_angle
from thymio_bt.logs.entries import TickRecord, checked_events, finite
from thymio_bt.logs.recording import Recording
from thymio_bt.robot.interface import ROBOT_ENTITY, Backend, Collision, Request, Scan, Twist
from thymio_bt.robot.model import DEFAULT_ROBOT, RobotModel, robot_model

#: the entity events a recorded run's deletes and spawns left, by the request kind
ENTITY_EVENTS = {"delete_entity": "delete", "spawn_entity": "spawn"}


class RecordedRobot(Backend):
    """The robot of a recording, one recorded tick per :meth:`advance` (see the module docstring).
    ``model`` is the robot the log was made with (the course's by default); ``latency`` the
    backend's (the log's header says it, where it was written since logs carry it)."""

    def __init__(self, recording: Recording, model: RobotModel | None = None, latency: float | None = None) -> None:
        super().__init__()
        self.samples = recording.samples
        self.model = model or robot_model(DEFAULT_ROBOT)
        self.latency = (finite(recording.header.get("latency")) or 0.0) if latency is None else latency
        #: the recorded tick now served (0: the first tick)
        self.index = 0
        #: the entity requests served so far, as (kind, entity, pose or None), the start's spawn included
        self.served: list[tuple[str, str, dict[str, float] | None]] = []
        self._cmd = Twist()
        self._crashes = [e for e in checked_events(recording.events) if e.get("kind") == "collision"]
        #: when each recorded delete or spawn was served (its event's time), in order
        self.entity_events = entity_events(recording)
        #: the live backend every call goes to once :meth:`go_live` is called, with its clock's offset
        self.live: Backend | None = None
        self._since = 0.0
        self._frame = (0.0, 0.0, 0.0)  # live ground truth -> the recorded odometry's frame

    @property
    def sample(self) -> TickRecord:
        """The recorded tick being served."""
        return self.samples[min(self.index, len(self.samples) - 1)]

    # ------------------------------------------------------------ the robot
    def drive(self, linear: float, angular: float) -> None:
        """Keep the command (a live backend acts on it)."""
        if self.live is not None:
            self.live.drive(linear, angular)
        elif self.exists():
            self._cmd = Twist(float(linear), float(angular))

    def exists(self) -> bool:
        """Whether the robot existed at this tick (a log has a pose or readings for it then)."""
        if self.live is not None:
            return self.live.exists()
        return self.sample.get("pose") is not None or self.sample.get("prox") is not None

    def proximity(self) -> Scan | None:
        """The recorded readings (None, out of range, as infinity)."""
        if self.live is not None:
            return self.live.proximity()
        prox = self.sample.get("prox")
        return None if prox is None else {k: math.inf if v is None else v for k, v in prox.items()}

    def pose(self) -> Pose | None:
        """The recorded odometry pose (the logged pose where odometry was the pose)."""
        if self.live is not None:
            truth = self.live.pose()
            return None if truth is None else _compose(self._frame, truth)
        pose = self.sample.get("odom") or self.sample.get("pose")
        return None if pose is None else new_pose(pose["x"], pose["y"], pose["yaw"])

    def true_pose(self) -> Pose | None:
        """The recorded pose (ground truth where the backend had it)."""
        if self.live is not None:
            return self.live.true_pose()
        pose = self.sample.get("pose")
        return None if pose is None else new_pose(pose["x"], pose["y"], pose["yaw"])

    def velocity(self) -> Twist:
        """The recorded measured velocity."""
        if self.live is not None:
            return self.live.velocity()
        linear, angular = self.sample.get("vel") or (0.0, 0.0)
        return Twist(linear, angular)

    def command(self) -> Twist:
        """The command the tree gave last."""
        return self.live.command() if self.live is not None else self._cmd

    def time(self) -> float:
        """The recorded tick's time (a live backend's, counted from where it took over)."""
        if self.live is not None:
            return round(self._since + self.live.time(), 9)
        return float(self.sample["t"])

    # ----------------------------------------------------------- stepping
    def advance(self, duration: float) -> None:
        """Go to the next recorded tick (``duration`` > 0), note its collisions, serve the requests."""
        if self.live is not None:
            self.live.advance(duration)
            self.collisions, self.min_clearance = self.live.collisions, self.live.min_clearance
            return
        if duration > 0:
            self.index += 1
        t = self.time()
        while self._crashes and self._crashes[0]["t"] <= t + 1e-9:
            crash = self._crashes.pop(0)
            self.collisions.append(Collision(crash["t"], crash.get("x") or 0.0, crash.get("y") or 0.0))
        self.serve_requests()

    def serve_requests(self) -> None:
        """Serve the requests the recorded run had served by now: the n-th delete or spawn once the
        recording's n-th entity event has happened (the start's spawn at once), as slowly as the
        recorded backend did (a ROS 2 service takes ticks); one the recording lacks at once."""
        ready: list[Request] = []
        while self._requests and self._due(len(self.served) + len(ready)):
            ready.append(self._requests.pop(0))
        later, self._requests = self._requests, ready
        super().serve_requests()
        self._requests = later

    def _due(self, n: int) -> bool:
        """Whether the ``n``-th request (0: the start's spawn) is served by this tick."""
        if n == 0 or n > len(self.entity_events):
            return True
        return bool(self.entity_events[n - 1]["t"] <= self.time() + 1e-9)

    def request_delete(self, name: str) -> Request:
        """Queue a delete (served at the next tick; by the live backend once there is one)."""
        return self.live.request_delete(name) if self.live is not None else super().request_delete(name)

    def request_spawn(self, name: str, pose: Pose) -> Request:
        """Queue a spawn (served at the next tick; by the live backend once there is one)."""
        return self.live.request_spawn(name, pose) if self.live is not None else super().request_spawn(name, pose)

    def spawn_problem(self, name: str, pose: Pose) -> str | None:
        """Nothing stops a recorded spawn: the recording says whether the robot was there."""
        return self.live.spawn_problem(name, pose) if self.live is not None else None

    def _remove(self, name: str) -> str | None:
        self.served.append(("delete", name, None))
        return None

    def _place_entity(self, name: str, pose: Pose) -> str | None:
        self.served.append(("spawn", name, _rounded(pose)))
        return None

    def requests(self) -> list[tuple[str, str, dict[str, float] | None]]:
        """The entity requests made so far, served or pending, as (kind, entity, pose or None)."""
        pending = [(r.kind, r.entity, None if r.pose is None else _rounded(r.pose)) for r in self._requests]
        return self.served + pending

    def go_live(self, live: Backend) -> None:
        """Hand every call from now on to ``live``, whose robot stands at this tick's recorded pose:
        its clock continues this tick's, its odometry continues the recorded one."""
        truth, odom = live.true_pose(), self.pose()
        if truth is not None and odom is not None:  # odom = frame ∘ truth
            yaw = wrap_angle(odom.yaw - truth.yaw)
            c, s = math.cos(yaw), math.sin(yaw)
            self._frame = (odom.x - (c * truth.x - s * truth.y), odom.y - (s * truth.x + c * truth.y), yaw)
        self._since = self.time() - live.time()
        self.latency = live.latency  # behaviours that start from now on lead by the live robot's
        self.live = live

    def close(self) -> None:
        """Close the live backend, if any."""
        if self.live is not None:
            self.live.close()


def entity_events(recording: Recording) -> list[dict[str, Any]]:
    """The deletes and spawns of a recorded run, as its events give them; for a log without its end
    (cut short, damaged), where the ticks show the robot disappear and reappear."""
    if recording.events or recording.end.get("status") != "INCOMPLETE":
        return [e for e in checked_events(recording.events) if e.get("kind") in ENTITY_EVENTS]
    found: list[dict[str, Any]] = []
    there = True  # the start's spawn
    for sample in recording.samples:
        pose = sample.get("pose")
        if (pose is not None) != there:
            there = pose is not None
            kind = "spawn_entity" if there else "delete_entity"
            found.append({"t": sample["t"], "kind": kind, "entity": ROBOT_ENTITY, **({"pose": pose} if there else {})})
    return found


def _rounded(pose: Pose) -> dict[str, float]:
    """A pose as logs keep it."""
    return {k: round(v, 6) for k, v in pose.as_dict().items()}


def _compose(frame: tuple[float, float, float], pose: Pose) -> Pose:
    """``pose`` seen through the rigid transform ``frame`` (dx, dy, dyaw)."""
    if frame == (0.0, 0.0, 0.0):
        return pose  # the same frame: the live pose as it is, bit for bit
    dx, dy, yaw = frame
    c, s = math.cos(yaw), math.sin(yaw)
    return Pose(dx + c * pose.x - s * pose.y, dy + s * pose.x + c * pose.y, wrap_angle(pose.yaw + yaw))
