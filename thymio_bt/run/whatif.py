"""What if: tick another tree (or the same, changed) against a recorded run.

Every tick the tree reads the recording (:class:`~thymio_bt.run.recorded.RecordedRobot`: readings,
odometry, clock, entity events), never a simulation. While its commands equal the recorded ones
(within ``tolerance``, the log's rounding) and it asks for the entity deletes and spawns the
recorded run made, the recording is exactly what the robot would have sensed, and the verdict is
exact. At the first tick where it decides differently the replay stops there and says so
(:class:`CommandDivergence`); with ``continue_sim`` the simulator takes over from the recorded
state at that tick (the ground-truth pose where the log has one, else the odometry) and the rest
of the run is simulated.

Example (the mission's stop distance changed from 5 to 6 cm, replayed against a 5 cm run):

>>> from thymio_bt.logs.recording import Recorder
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> recorder = Recorder(statuses=True)
>>> recording = recorder.finish(Run(load_mission("maze_part1_2")).run(on_tick=recorder))
>>> same = what_if(recording, load_mission("maze_part1_2"))
>>> same.divergence, same.result.status, same.replayed_ticks
(None, <RunStatus.SUCCESS: 'SUCCESS'>, 329)
>>> changed = what_if(recording, load_mission("maze_part1_2", {"final_stop": "6cm"}))
>>> changed.divergence.node, changed.divergence.time, changed.divergence.to_json()["tick"]
('course/part 1', 3.6, 37)
>>> print(changed.divergence.text)  # doctest: +NORMALIZE_WHITESPACE
from 3.6 s (tick 37) the recording no longer tells what the robot would see:
course/part 1 (MoveUntilWall) commanded [0.096504, 0.0] where the recording has [0.1, 0.0]
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from py_trees.behaviour import Behaviour

from thymio_bt.behaviours.base import node_path
from thymio_bt.behaviours.flow.node import node_kind
from thymio_bt.errors import Problem, StopRun, UserError
from thymio_bt.geometry import new_pose
from thymio_bt.logs.entries import STATUS_LETTER, TickRecord, finite
from thymio_bt.logs.recording import Recording
from thymio_bt.plan.model import Mission
from thymio_bt.robot.interface import Backend
from thymio_bt.robot.model import ROBOTS
from thymio_bt.run.divergence import pose_source
from thymio_bt.run.recorded import ENTITY_EVENTS, RecordedRobot
from thymio_bt.run.runner import Run, RunResult

#: how far a command may be from the recorded one and still be the same (m/s, rad/s): JSON-lines
#: logs keep exact numbers; one written before they named their backend keeps 6 decimals, a rosbag2
#: log float32 scans (its header says ``exact: false``), and then the commands computed from them
#: are compared within :data:`ROUNDED_TOLERANCE`
COMMAND_TOLERANCE = 1e-9
ROUNDED_TOLERANCE = 1e-4


@dataclass(frozen=True)
class CommandDivergence:
    """The first tick the replayed tree decided differently: its ``time`` and ``tick``, the ``node``
    that did (its path; ``kind`` its type), and the ``recorded`` and ``new`` commands ([linear,
    angular], as exact as the log has them) or entity requests ("delete thymio")."""

    time: float
    tick: int
    node: str
    kind: str
    recorded: Any
    new: Any

    def to_json(self) -> dict[str, Any]:
        """The report's ``counterfactual.divergence``: ``time``, ``tick``, ``node``, ``recorded``, ``new``."""
        return {"time": self.time, "tick": self.tick, "node": self.node, "recorded": self.recorded, "new": self.new}

    @property
    def text(self) -> str:
        """The divergence in a sentence."""
        return (
            f"from {self.time:g} s (tick {self.tick}) the recording no longer tells what the robot would see: "
            f"{self.node} ({self.kind}) commanded {_shown(self.new, self.recorded)} where the recording has "
            f"{_shown(self.recorded, self.new)}"
        )


@dataclass
class WhatIf:
    """A what-if replay's outcome: the run's ``result``, its ``divergence`` (None: the tree did what
    the recorded one did throughout), how many ticks were replayed and simulated, and ``notes`` (a
    recording that ended or was damaged before the tree did, where the simulation started from)."""

    result: RunResult
    divergence: CommandDivergence | None
    replayed_ticks: int
    simulated_ticks: int
    notes: list[str]
    #: how far the commands could be from the recorded ones and count as the same
    tolerance: float = COMMAND_TOLERANCE

    def counterfactual(self) -> dict[str, Any]:
        """The report's ``counterfactual`` section."""
        return {
            "divergence": None if self.divergence is None else self.divergence.to_json(),
            "replayed_ticks": self.replayed_ticks,
            "simulated_ticks": self.simulated_ticks,
        }

    def report(self) -> dict[str, Any]:
        """The run report, as ``run`` writes it, with its ``counterfactual`` section."""
        return {**self.result.report(), "counterfactual": self.counterfactual()}


def what_if(
    recording: Recording,
    mission: Mission,
    *,
    continue_sim: bool = False,
    tolerance: float | None = None,
    on_tick: Callable[[Run], None] | None = None,
) -> WhatIf:
    """Replay ``mission``'s tree against ``recording`` (see the module docstring); ``on_tick`` sees
    every tick after the check (a recorder, say). ``tolerance``: on the commands, by default
    :data:`COMMAND_TOLERANCE` (:data:`ROUNDED_TOLERANCE` for an older log, whose numbers are rounded).
    A recording of another mission is refused."""
    if not recording.samples:
        raise UserError(Problem("the log has no tick to replay", recording.mission or "the log"))
    rate = finite(recording.header.get("tick_hz"))
    if rate is not None and rate != mission.tick_hz:
        raise UserError(
            Problem(
                f"the log was recorded at {rate:g} Hz, the mission ticks at {mission.tick_hz:g} Hz",
                recording.mission or "the log",
                hint=f"replay with --set tick_hz={rate:g}",
            )
        )
    # the maze the recorded run was in, and the robot it ran (the log header names it)
    mission = dataclasses.replace(mission, maze=recording.maze, robot=_robot_name(mission, recording))
    robot = RecordedRobot(recording, _model(mission, recording))
    seed = recording.header.get("seed")
    run = Run(mission, seed if isinstance(seed, int) and 0 <= seed < 2**63 else mission.seed, backend=robot)
    _check_tree(recording, run.root)
    if tolerance is None:
        exact = "backend" in recording.header and recording.header.get("exact", True)
        tolerance = COMMAND_TOLERANCE if exact else ROUNDED_TOLERANCE
    watch = _Watch(recording, robot, mission, tolerance, continue_sim)

    def hooks(r: Run) -> None:
        watch(r)
        if on_tick is not None:
            on_tick(r)

    result = run.run(on_tick=hooks)
    return WhatIf(result, watch.divergence, watch.replayed, watch.simulated, watch.notes, tolerance)


def _robot_name(mission: Mission, recording: Recording) -> str | None:
    """The built-in robot the log says ran (its header's ``robot``), else the mission's: the changed
    tree is re-ticked, and simulated on with ``--continue sim``, as that robot."""
    ran = recording.header.get("robot")
    name = ran.get("name") if isinstance(ran, dict) else None
    return name if isinstance(name, str) and name in ROBOTS else mission.robot


def _model(mission: Mission, recording: Recording) -> Any:
    """The robot model the recorded run had: the mission's, else its backend's own."""
    from thymio_bt.backends import backend_kind, robot_for

    backend = str(recording.header.get("backend", "sim"))
    try:
        backend_kind(backend)
    except UserError:
        backend = "sim"  # a backend not installed here: the mission's robot
    return robot_for(mission, backend, say=lambda _: None)


def _check_tree(recording: Recording, root: Behaviour) -> None:
    """Refuse a recording whose tree ran nodes this tree lacks: a log of another mission."""
    paths = {node_path(n) for n in root.iterate()}
    ran: dict[str, None] = {}
    for sample in recording.samples:
        for path, status in (sample.get("nodes") or {}).items():
            if status != "-" and path not in paths:
                ran.setdefault(path)
    if ran:
        missing = list(ran)
        more = f" and {len(missing) - 3} more" if len(missing) > 3 else ""
        raise UserError(
            Problem(
                f"the log is of another tree: its run ran {', '.join(missing[:3])}{more}, which this mission lacks",
                recording.mission or "the log",
                hint="replay a log of this mission (its node names kept), or run both and use thymio-bt compare",
            )
        )


class _Watch:
    """The tick hook of a what-if replay: checks each tick's command against the recorded one and
    stops (or hands over to the simulator) at the first difference."""

    def __init__(
        self, recording: Recording, robot: RecordedRobot, mission: Mission, tolerance: float, continue_sim: bool
    ) -> None:
        self.recording, self.robot, self.mission = recording, robot, mission
        self.tolerance, self.continue_sim = tolerance, continue_sim
        self.divergence: CommandDivergence | None = None
        self.replayed = self.simulated = 0
        self.notes: list[str] = []

    def __call__(self, run: Run) -> None:
        robot = self.robot
        if robot.live is not None:
            self.simulated += 1
            return
        sample = robot.sample
        self.divergence = self._difference(run, sample)
        self.replayed += 1
        if self.divergence is not None:
            self._diverged(run)
        elif robot.index >= len(robot.samples) - 1 and run.root.status.name == "RUNNING" and not _last_tick(run):
            self._recording_ends(run)

    def _difference(self, run: Run, sample: TickRecord) -> CommandDivergence | None:
        """How this tick differs from the recorded one (the command, the entity requests), or None."""
        new = run.backend.command()
        recorded = sample.get("cmd") or [0.0, 0.0]
        if abs(new.linear - recorded[0]) > self.tolerance or abs(new.angular - recorded[1]) > self.tolerance:
            return self._divergence(run, sample, list(recorded), [new.linear, new.angular])
        recorded_requests = [
            (e["t"], _request_text(ENTITY_EVENTS[e["kind"]], str(e.get("entity", "")), e.get("pose")))
            for e in self.robot.entity_events
        ]
        made = [_request_text(*r) for r in self.robot.requests()[1:]]  # the first: the start's spawn
        # the new tree asks for what the recorded one did, in order; what the recording had served by now
        # (an event is written once the request is served) it has asked for too
        expected = [text for _, text in recorded_requests[: len(made)]]
        served = sum(1 for t, _ in recorded_requests if t <= sample["t"] + 1e-9)
        if made != expected or len(made) < served:
            i = next(
                (i for i, (m, e) in enumerate(zip(made, expected, strict=False)) if m != e), min(len(made), served)
            )
            asked = recorded_requests[i][1] if i < len(recorded_requests) else None
            return self._divergence(run, sample, asked, made[i] if i < len(made) else None)
        return None

    def _divergence(self, run: Run, sample: TickRecord, recorded: Any, new: Any) -> CommandDivergence:
        """The divergence at this tick, naming the node that decided differently: the deepest node
        whose status differs from the recorded one, else the running leaf."""
        nodes = {node_path(n): n for n in run.root.iterate()}
        logged = sample.get("nodes") or {}
        differ = [p for p, n in nodes.items() if p in logged and STATUS_LETTER[n.status.name] != logged[p]]
        deepest = [p for p in differ if not any(q.startswith(p + "/") for q in differ)]
        running = [p for p, n in nodes.items() if not n.children and n.status.name == "RUNNING"]
        path = (deepest or running or [node_path(run.root)])[0]
        return CommandDivergence(sample["t"], run.ticks, path, node_kind(nodes[path]), recorded, new)

    def _diverged(self, run: Run) -> None:
        """Stop the replay at the divergence, or go on in the simulator from the recorded state."""
        assert self.divergence is not None
        if not self.continue_sim:
            raise StopRun(self.divergence.text)
        self._go_live(run, f"{self.divergence.text}; simulated from there")

    def _recording_ends(self, run: Run) -> None:
        """The recording has no tick after this one while the tree goes on."""
        t = self.robot.sample["t"]
        damaged = self.recording.header.get("damaged_at")
        why = f"the log is damaged at line {damaged}" if damaged else "the recording ends"
        if self.recording.end.get("status") == "INCOMPLETE" and not damaged:
            why = "the log is cut short"
        text = f"{why} at {t:g} s (tick {run.ticks}) with the tree still running"
        if not self.continue_sim:
            raise StopRun(f"{text} (hint: --continue sim goes on in the simulator)")
        self._go_live(run, f"{text}; simulated from there")

    def _go_live(self, run: Run, note: str) -> None:
        """Put a simulator's robot in this tick's recorded state and hand the run to it."""
        from thymio_bt.backends import backend_kind

        robot, sample = self.robot, self.robot.sample
        source = pose_source(self.recording)
        mission = self.mission
        if robot.model.name in ROBOTS:  # the recorded backend's own robot (Enki's on the Playground)
            mission = dataclasses.replace(mission, robot=robot.model.name)
        sim: Backend = backend_kind("sim").create(mission, run.seed)
        pose = sample.get("pose")
        if pose is not None:
            sim.request_spawn(robot.robot_name, new_pose(pose["x"], pose["y"], pose["yaw"]))
            sim.advance(0.0)
            linear, angular = sample.get("cmd") or (0.0, 0.0)
            sim.drive(linear, angular)  # the recorded command drives until the new one acts
            sim.advance(0.0)
        new = robot.command()
        robot.go_live(sim)
        sim.drive(new.linear, new.angular)
        start = "the ground-truth pose" if source == "ground truth" else f"the {source} pose (no ground truth)"
        self.notes.append(f"{note}, starting at {start} of that tick")


def _last_tick(run: Run) -> bool:
    """Whether this is the run's last tick: its time limit ends it now, as it ended the recorded one."""
    return run.ticks >= math.ceil(run.mission.time_limit * run.mission.tick_hz - 1e-9)


def _shown(value: Any, other: Any) -> Any:
    """A command with 6 decimals, as the messages print it, or all of them where 6 do not tell it
    from ``other`` (an entity request as it is)."""
    if isinstance(value, list) and all(isinstance(v, float) for v in value):
        short = [round(v, 6) for v in value]
        return short if short != [round(v, 6) for v in other or []] else value
    return value


def _request_text(kind: str, entity: str, pose: dict[str, float] | None) -> str:
    """An entity request in words: "delete thymio", "spawn thymio at (0.5, 0.3, 1.5708)"."""
    if kind == "spawn" and pose:
        return f"spawn {entity} at ({pose['x']:.4g}, {pose['y']:.4g}, {pose['yaw']:.4g})"
    return f"{kind} {entity}"
