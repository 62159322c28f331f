"""What every thymio-bt behaviour shares: the robot context, events, failure codes, time limits.

A behaviour is a :class:`py_trees.behaviour.Behaviour` built from a pydantic ``Params`` model and a
:class:`Context`. Subclasses implement :meth:`RobotBehaviour.start` and :meth:`RobotBehaviour.step`
(and :meth:`RobotBehaviour.prepare` to attach blackboard keys);
the base class handles the simulated-time limit, a deleted robot, collisions, stopping the robot
when the behaviour ends or is interrupted, and the ``behaviour_start``/``behaviour_end`` events.

Example::

    >>> class CreepParams(BehaviourParams):
    ...     "Creep forward."
    >>> class Creep(RobotBehaviour):
    ...     "Creep forward until something ends it (its YAML name is its class name)."
    ...     Params = CreepParams
    ...     moves = True
    ...     def step(self):
    ...         self.robot.drive(0.01, 0.0)
    ...         return Status.RUNNING
    >>> from thymio_bt.backends.sim import Simulation
    >>> from thymio_bt.behaviours.flow.ticking import tick
    >>> from thymio_bt.testing import world
    >>> sim = Simulation(world("corridor"), spawn=Pose(0.1, 0.1, 0.0))
    >>> ctx = Context(robot=sim, entities=sim)
    >>> creep = Creep("creep", CreepParams(), ctx)
    >>> tick(creep)
    >>> creep.status, sim.command().linear, [e["kind"] for e in ctx.events]
    (<Status.RUNNING: 'RUNNING'>, 0.01, ['behaviour_start'])
    >>> creep.stop(Status.INVALID)  # halted by a parent: the robot stops, the end is logged
    >>> sim.command().linear, ctx.events[-1]["status"]
    (0.0, 'INVALID')
"""

from __future__ import annotations

import math
import re
import signal
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Literal

import py_trees
from py_trees.common import Access, Status
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from thymio_bt.enums import FailureCode
from thymio_bt.geometry import Pose
from thymio_bt.inputs.fields import IN_SI, Duration
from thymio_bt.maze.model import Area
from thymio_bt.robot.interface import Entities, Robot

_CODE = re.compile(r"[A-Z][A-Z0-9_]*")
#: the statuses as module constants: ``Status.RUNNING`` is an attribute of an Enum class, which on
#: CPython 3.11 goes through ``EnumType.__getattr__``'s slot (about 1 k instructions a read, against
#: a few dozen for a global); behaviours return one every tick
RUNNING, SUCCESS, FAILURE, INVALID = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID
_DEBUG = py_trees.logging.Level.DEBUG


def describe(exc: BaseException) -> str:
    """An exception in one line: its type, the last line of its message, and where it was raised
    (an exception whose ``str()`` itself raises is described by its type alone).

    >>> class Mute(Exception):
    ...     def __str__(self):
    ...         raise ValueError("no words")
    >>> describe(Mute()), describe(SystemExit(0))
    ('Mute (its message could not be read)', 'SystemExit: 0')
    """
    try:
        lines = str(exc).strip().splitlines()
    except Exception:  # a plugin's exception whose __str__ is broken: its type still says something
        lines = ["(its message could not be read)"]
        text = f"{type(exc).__name__} {lines[0]}"
    else:
        text = type(exc).__name__ + (f": {lines[-1]}" if lines else "")
    frames = traceback.extract_tb(exc.__traceback__)
    if frames:
        text += f" (at {Path(frames[-1].filename).name}:{frames[-1].lineno})"
    return text


def is_fault(exc: BaseException) -> bool:
    """Whether ``exc``, raised by a node's (a plugin's) code, is a fault of that code that fails the
    node: any exception, ``SystemExit`` and other BaseExceptions such as ``asyncio.CancelledError``;
    not ``GeneratorExit``, nor a ``KeyboardInterrupt`` that may be Ctrl-C's: a subclass (the runner's
    second signal) or any while Ctrl-C raises one (Python's default SIGINT handler is installed;
    ``thymio-bt run`` and the sweep workers replace it, so a plugin's own raise is its fault there).

    >>> import asyncio
    >>> is_fault(asyncio.CancelledError()), is_fault(SystemExit(0)), is_fault(KeyboardInterrupt())
    (True, True, False)
    """
    if isinstance(exc, KeyboardInterrupt):
        return type(exc) is KeyboardInterrupt and signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    return not isinstance(exc, GeneratorExit)


class EventLog(list):
    """The run's events, in time order: dicts with at least ``t`` and ``kind``."""

    def emit(self, t: float, kind: str, **fields: Any) -> None:
        """Append an event of ``kind`` at time ``t`` (rounded to the microsecond) with ``fields``."""
        self.append({"t": round(t, 6), "kind": kind, **fields})


@dataclass
class Context:
    """Everything a behaviour may use: the robot interfaces, the clock, events and the map bounds."""

    robot: Robot
    entities: Entities
    events: EventLog = field(default_factory=EventLog)
    tick_period: float = 0.1
    #: (xmin, ymin, xmax, ymax) of the known map, for "leave the maze" stop conditions.
    bounds: tuple[float, float, float, float] | None = None
    #: the maze's goal region, its areas (e.g. a micromouse maze's centre): ``Area.contains`` says
    #: whether a point is in one, as the run's report and ``expect:`` ask it
    goal: tuple[Area, ...] = ()
    #: How many collisions the backend has counted so far (a backend without a bumper returns 0).
    collision_count: Callable[[], int] = lambda: 0

    def now(self) -> float:
        """The backend's clock (simulated seconds in a simulation)."""
        return self.robot.time()


class BehaviourParams(BaseModel):
    """Parameters every robot behaviour accepts."""

    # defer_build: a model's validator is built when first used, not when its module is imported
    # (a run builds only its mission's behaviours' models: ~10 ms less start-up)
    model_config = ConfigDict(extra="forbid", defer_build=True)
    timeout: Duration = Field(60.0, gt=0, le=3600, description="time limit in simulated seconds")


def snapshot(robot: Robot) -> dict[str, Any]:
    """The robot's pose and proximity for an event (None when the robot does not exist)."""
    pose = robot.pose()
    scan = robot.proximity()
    return {
        "pose": None if pose is None else {k: round(v, 6) for k, v in pose.as_dict().items()},
        "proximity": None if scan is None else {k: (None if math.isinf(v) else round(v, 6)) for k, v in scan.items()},
    }


def node_path(node: py_trees.behaviour.Behaviour) -> str:
    """The slash-separated names from the root to ``node``."""
    names = []
    current: py_trees.behaviour.Behaviour | None = node
    while current is not None:
        names.append(current.name)
        current = current.parent
    return "/".join(reversed(names))


class Explains:
    """A node that says why it failed: :attr:`failure` is (code, reason) once it has, else None. The
    run's report follows a FAILURE down the tree to the node that explains it (robot behaviours, and
    the time limits of both vocabularies: ``timeout`` and BT.CPP's ``Timeout``)."""

    failure: tuple[FailureCode | str, str] | None = None


class RobotBehaviour(Explains, py_trees.behaviour.Behaviour):
    """Base of the behaviours that act on or sense the robot."""

    #: The name used in mission YAML and in events: the class's name unless its body sets one.
    yaml_name: ClassVar[str] = ""
    #: The pydantic model of the parameters.
    Params: ClassVar[type[BaseModel]] = BehaviourParams
    #: Whether the behaviour commands motion (and so stops the robot when it ends).
    moves: ClassVar[bool] = False
    #: Whether it emits behaviour_start/behaviour_end events (conditions, ticked often, do not).
    emits_events: ClassVar[bool] = True
    #: Whether it needs the robot to exist (fails with NO_ROBOT otherwise).
    needs_robot: ClassVar[bool] = True
    #: Whether it fails with COLLISION when the robot hits a wall while it runs.
    fails_on_collision: ClassVar[bool] = True
    #: Whether a BT.CPP control node ticks it again once it completed (BT.CPP's SyncActionNode, as
    #: every condition); otherwise it keeps its result until reset, as a StatefulActionNode.
    bt_sync: ClassVar[bool] = False
    #: What its behaviour_end event reports for the tools that read a run: "stop" (it stopped at a
    #: wall: ``range``, the reading then, against ``distance``, the stop asked; a sweep's
    #: ``first_stop_error``), "turn" (it turned in place: ``angle``; the path plot outlines the robot)
    reports: ClassVar[Literal["stop", "turn"] | None] = None
    #: For the lint: "S" (or "F") when it always ends so, in the tick it starts; and whether it ends
    #: in that tick although it is an action (``Stop``, ``PlanMove``), not a condition
    always: ClassVar[str] = ""
    instant: ClassVar[bool] = False
    #: Whether it is a condition: it answers at once, SUCCESS (true) or FAILURE (false)
    condition: ClassVar[bool] = False

    #: behaviours made in this process: the pytest plugin clears the blackboard after tests that made some
    created = 0
    #: the feedback line, or a template and its arguments not formatted yet (see :meth:`say`)
    _feedback: str | tuple[str, tuple[Any, ...]]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Name the subclass: its own ``yaml_name``, else its class name (never its parent's)."""
        super().__init_subclass__(**kwargs)
        if "yaml_name" not in cls.__dict__:
            cls.yaml_name = cls.__name__

    def __init__(
        self, name: str, params: BaseModel, ctx: Context, blackboard_refs: dict[str, str] | None = None
    ) -> None:
        super().__init__(name=name)
        RobotBehaviour.created += 1
        self.declared = params
        self.params: Any = params
        self.ctx = ctx
        self.robot = ctx.robot
        self.failure: tuple[FailureCode | str, str] | None = None
        #: fields added to the behaviour_end event: a dict, or a function giving one when the
        #: behaviour ends (a behaviour that updates them every tick saves rounding what nobody reads)
        self.extra: dict[str, Any] | Callable[[], dict[str, Any]] = {}
        self._refs = dict(blackboard_refs or {})
        self._reader: py_trees.blackboard.Client | None = None
        if self._refs:
            self._reader = self.attach_blackboard_client(name=f"{name}_reads")
            for key in self._refs.values():
                self._reader.register_key(key, access=Access.READ)
        self._start_time = 0.0
        self._collisions_at_start = 0
        self._path: str | None = None
        self.prepare()

    @classmethod
    def clear_ahead(cls, params: Any) -> float | None:
        """For the lint's ``checked-once``: how far (m) the way ahead is clear when this condition,
        with ``params``, is false (``invert: WallAhead``); None (the default): it says nothing of it."""
        return None

    @classmethod
    def drives_forward(cls, params: Any) -> float:
        """For the lint's ``checked-once``: how far (m; ``math.inf``: no bound) this action, with
        ``params``, drives forward without looking ahead itself; 0 (the default): it does not."""
        return 0.0

    # ---------------------------------------------------------------- hooks
    def prepare(self) -> None:
        """Called once, when the node is built (``self.params`` set, the robot perhaps not there yet:
        a tree is also built to be drawn): attach blackboard clients (:meth:`blackboard`), parse code."""

    def start(self) -> None:
        """Called when the behaviour starts (after parameters are resolved)."""

    def step(self) -> Status:
        """One tick of work; return RUNNING, SUCCESS, or ``self.fail(...)``."""
        return Status.SUCCESS

    # ---------------------------------------------------------- machinery
    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """py_trees' ``Behaviour.tick``: :meth:`tick_direct`, then yield the node."""
        self.tick_direct()
        yield self

    def tick_direct(self) -> None:
        """py_trees' ``Behaviour.tick`` without its per-tick debug string and status list, nor a
        generator: the same initialise → update → stop sequence (see :mod:`.flow.ticking`)."""
        try:
            if self.status is not RUNNING:
                self.initialise()
            new_status = self.update()
        except BaseException as exc:  # a plugin's bug (or ours): fail the node, say where
            if not is_fault(exc):
                raise
            new_status = self.fail(FailureCode.EXCEPTION, f"{self.yaml_name} raised {describe(exc)}")
        if new_status.__class__ is not Status:  # a plugin's bug: fail the node, say why
            new_status = self.fail(
                FailureCode.FAILED, f"{self.yaml_name} returned {_safe_repr(new_status)}, not a Status"
            )
        if new_status is not RUNNING:
            self.stop(new_status)
            return  # stop() set the status: FAILURE if the node's terminate() raised
        self.status = new_status

    def stop(self, new_status: Status) -> None:
        """py_trees' ``Behaviour.stop``, its debug line built only when py_trees logs at debug level
        (it formats two statuses on every stop, logged or not)."""
        try:
            if py_trees.logging.level is _DEBUG:
                super().stop(new_status)
                return
            self.terminate(new_status)
        except BaseException as exc:  # a plugin's terminate() raised: the node fails, the robot stops
            if not is_fault(exc):
                raise
            new_status = self._failed_terminate(new_status, exc)
        self.status = new_status
        self.iterator = self.tick()

    def _failed_terminate(self, new_status: Status, exc: BaseException) -> Status:
        """The status of a node whose ``terminate()`` raised ``exc``: FAILURE with code EXCEPTION (a
        halted node stays INVALID: its parent decides), its end logged and a moving robot stopped by
        the base class's ``terminate()``."""
        self.fail(FailureCode.EXCEPTION, f"{self.yaml_name} raised {describe(exc)} in terminate()")
        if new_status is not Status.INVALID:
            new_status = Status.FAILURE
        self.status = Status.RUNNING  # so that the base class logs the end even of a halted node
        try:
            RobotBehaviour.terminate(self, new_status)
        except BaseException as again:  # the robot or the events failed too: nothing more to do here
            if not is_fault(again):
                raise
        return new_status

    @property
    def feedback_message(self) -> str:
        """py_trees' one-line status of the node, formatted when read (see :meth:`say`)."""
        message = self._feedback
        if isinstance(message, tuple):
            template, args = message
            message = self._feedback = template.format(*args)
        return message

    @feedback_message.setter
    def feedback_message(self, message: str) -> None:
        self._feedback = message

    def say(self, template: str, *args: Any) -> None:
        """Set the feedback line to ``template.format(*args)``, formatted only if something reads it
        (a display, the final tree): a line set every tick costs a float formatting each otherwise."""
        self._feedback = (template, args)

    @property
    def path(self) -> str:
        """The node's path from the root (names joined by ``/``), found once the tree is built."""
        if self._path is None:
            self._path = node_path(self)
        return self._path

    def elapsed(self) -> float:
        """Seconds of backend time since the behaviour started."""
        return self.ctx.now() - self._start_time

    def fail(self, code: FailureCode | str, reason: str) -> Status:
        """Record why the behaviour fails (a :class:`FailureCode` or a plugin's own UPPER_SNAKE_CASE
        code) and return FAILURE."""
        if not _CODE.fullmatch(code):
            raise ValueError(f"failure code {str(code)!r} must be UPPER_SNAKE_CASE, e.g. LINE_LOST")
        self.failure = (code, reason)
        self.feedback_message = f"{code}: {reason}"
        return Status.FAILURE

    def initialise(self) -> None:
        """py_trees' hook when the node starts: reset, resolve blackboard parameters, log the start,
        then :meth:`start` (unless the robot is missing or a parameter could not be resolved)."""
        self.failure = None
        self.extra = {}
        self.feedback_message = ""
        self._start_time = self.ctx.now()
        self._collisions_at_start = self.ctx.collision_count()
        self._resolution_error = self._resolve_refs()
        if self.emits_events:
            self.ctx.events.emit(self._start_time, "behaviour_start", name=self.yaml_name, path=self.path)
        if self._resolution_error is None and (self.robot.exists() or not self.needs_robot):
            self.start()

    def _resolve_refs(self) -> str | None:
        """Validate the parameters again with the blackboard values they refer to; why not, or None."""
        if not self._refs:
            return None
        values = {}
        assert self._reader is not None
        for param, key in self._refs.items():
            if not self._reader.exists(key):
                return f"blackboard key '{key}' (for '{param}') has not been written yet"
            values[param] = self._reader.get(key)
        model = type(self.declared)
        try:
            self.params = model.model_validate({**self.declared.model_dump(), **values}, context=IN_SI)
        except ValidationError as exc:  # a bad value on the blackboard: said as a mission's would be
            from thymio_bt.inputs.validation import problems_from

            said = "; ".join(str(p) for p in problems_from(exc, values, "", model))
            return f"blackboard value for {', '.join(values)} is invalid: {said}"
        except Exception as exc:  # a plugin's validator that raised something else
            return f"blackboard value for {', '.join(values)} is invalid: {exc}"
        return None

    def update(self) -> Status:
        """py_trees' hook each tick: the shared checks (parameters, robot, collisions), then
        :meth:`step`, then the time limit."""
        if self._resolution_error is not None:
            return self.fail(FailureCode.INVALID_INPUT, self._resolution_error)
        if self.needs_robot and not self.robot.exists():
            return self.fail(FailureCode.NO_ROBOT, "the robot does not exist (was it deleted?)")
        if self.fails_on_collision and self.ctx.collision_count() > self._collisions_at_start:
            return self.fail(FailureCode.COLLISION, "the robot hit a wall")
        status = self.step()
        if status is RUNNING and self.robot.time() - self._start_time >= self.params.timeout - 1e-9:
            return self.on_timeout()
        return status

    def on_timeout(self) -> Status:
        """What running out of time means; subclasses may give a more precise code."""
        return self.fail(FailureCode.TIMEOUT, f"not done after {self.params.timeout:g} s")

    def blackboard(
        self, suffix: str, write: tuple[str, ...] = (), read: tuple[str, ...] = ()
    ) -> py_trees.blackboard.Client:
        """A blackboard client ``{name}_{suffix}`` with ``write`` then ``read`` keys registered."""
        board = self.attach_blackboard_client(name=f"{self.name}_{suffix}")
        for key in write:
            board.register_key(key, access=Access.WRITE)
        for key in read:
            board.register_key(key, access=Access.READ)
        return board

    def keeps_moving(self) -> bool:
        """Whether the robot is left driving when this moving behaviour ends (a motion's ``keep_moving``)."""
        return False

    def terminate(self, new_status: Status) -> None:
        """py_trees' hook when the node ends or is halted: stop a moving robot, log the end."""
        if self.status != RUNNING and new_status == INVALID:
            return  # a parent resetting a behaviour that already ended (or never started)
        if self.moves and not self.keeps_moving() and self.robot.exists():
            self.robot.drive(0.0, 0.0)
        if not self.emits_events:
            return
        event: dict[str, Any] = {"name": self.yaml_name, "path": self.path, "status": new_status.name}
        if self.failure is not None:
            event["code"], event["reason"] = self.failure
        event.update(self.extra if isinstance(self.extra, dict) else self.extra())
        event.update(snapshot(self.robot))
        self.ctx.events.emit(self.ctx.now(), "behaviour_end", **event)


class Reading(float):
    """A range reading as a condition's feedback says it: metres, or "nothing in range" for inf
    (formatted only when read, as :meth:`RobotBehaviour.say` is).

    >>> f"{Reading(0.0712)}", f"{Reading(math.inf)}"
    ('0.071 m', 'nothing in range')
    """

    def __format__(self, spec: str) -> str:
        return "nothing in range" if math.isinf(self) else f"{float(self):.3f} m"


class ConditionBehaviour(RobotBehaviour):
    """A check that answers SUCCESS or FAILURE at once, without events (guards tick them often)."""

    emits_events = False
    fails_on_collision = False
    bt_sync = True  # BT.CPP ticks a condition every time
    condition = True


class UnrunPlugin(RobotBehaviour):
    """The base of the stand-ins for plugin nodes whose code was not imported
    (:func:`thymio_bt.plan.unrun_plugins.stand_in`): validate, tree and lint read their names and
    parameters, and know nothing of what they do; they are never ticked."""


def _safe_repr(value: Any) -> str:
    """``repr(value)``, or its type's name when its ``__repr__`` raises (a plugin's broken object)."""
    try:
        return repr(value)
    except Exception:
        return f"a {type(value).__name__}"


def current_pose(robot: Robot) -> Pose:
    """The pose, for behaviours that already checked that the robot exists."""
    pose = robot.pose()
    assert pose is not None
    return pose


__all__ = [
    "BehaviourParams",
    "ConditionBehaviour",
    "Context",
    "EventLog",
    "Explains",
    "FAILURE",
    "FailureCode",
    "INVALID",
    "RUNNING",
    "Reading",
    "RobotBehaviour",
    "SUCCESS",
    "UnrunPlugin",
    "current_pose",
    "describe",
    "is_fault",
    "node_path",
    "snapshot",
]
