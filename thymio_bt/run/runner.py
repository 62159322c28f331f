"""The tick loop: tick the tree at the mission's rate in simulated time, advance the backend between
ticks, stop on SUCCESS, FAILURE or the time limit, and produce a :class:`RunResult`.

Example:

>>> from thymio_bt.mission import load_mission
>>> result = Run(load_mission("maze_part1_2")).run()
>>> result.status, round(result.sim_time, 1), result.ticks
(<RunStatus.SUCCESS: 'SUCCESS'>, 32.8, 329)
>>> report = result.report()
>>> report["status"], report["expectations"]
(<RunStatus.SUCCESS: 'SUCCESS'>, {'met': True, 'failed': []})

A run that the tree does not end is cut short, its running node named:

>>> result = Run(load_mission("maze_part1_2", {"time_limit": "5"})).run()
>>> result.status, result.code, result.reason, result.failed_path
(<RunStatus.TIMEOUT: 'TIMEOUT'>, <FailureCode.TIMEOUT: 'TIMEOUT'>, 'time limit of 5 s reached',
 'course/part 2/leg/approach/ChooseTurn')
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.backends import backend_kind
from thymio_bt.behaviours import Context, EventLog
from thymio_bt.behaviours.base import describe, is_fault, node_path, snapshot
from thymio_bt.behaviours.flow.ticking import TICK_OF
from thymio_bt.enums import FailureCode
from thymio_bt.errors import Problem, StopRun, UserError
from thymio_bt.geometry import Pose
from thymio_bt.mission import build_tree
from thymio_bt.plan.expect import Expect
from thymio_bt.plan.model import Mission
from thymio_bt.robot.interface import Backend, Collision, RequestState, RobotLost
from thymio_bt.robot.placement import MazeShapes
from thymio_bt.run.interrupts import Interrupted, Interrupts
from thymio_bt.run.phases import phases
from thymio_bt.run.result import (
    Ending,
    EndKind,
    GoalReached,
    RunOutcome,
    RunResult,
    RunStatus,
    failing_branch,
    learnt_map,
)

if TYPE_CHECKING:
    from thymio_bt.run.coverage import NodeStats

TickHook = Callable[["Run"], None]

#: a hull-to-wall gap at or below this (m) is contact, a collision: the report's ``min_clearance``
#: is rounded to 1 µm, so a report never says 0 clearance with 0 collisions (:meth:`Run._contact`)
CONTACT = 1e-6

#: the longest wait (s) of ``--realtime`` pacing before it looks for a signal again
PACE_SLICE = 0.1

#: the statuses that end a run, read once (an Enum class's attribute costs ~1 k instructions a read)
_ENDED = (Status.SUCCESS, Status.FAILURE)


class Run:
    """One prepared run of a mission on a backend (by default the pymunk simulation)."""

    def __init__(
        self,
        mission: Mission,
        seed: int | None = None,
        substitutions: dict[str, Any] | None = None,
        node_stats: bool = False,
        backend: Backend | None = None,
    ) -> None:
        """``backend`` defaults to the one the mission names (:mod:`thymio_bt.backends`; the pymunk
        simulation of its maze unless it says otherwise); the robot is spawned at the mission's start.
        The backend is the run's, given or not: :meth:`run` closes it however the run ends, and so does
        this constructor if the run cannot be prepared (an impossible start, a bad substitution), so
        that no caller has to guard it (a Playground process or a real robot's motors stay running
        otherwise)."""
        self.mission = mission
        self.seed = mission.seed if seed is None else seed
        self.backend: Backend = backend or backend_kind(mission.backend).create(
            mission, self.seed, mission.backend_options
        )
        try:
            self._prepare(substitutions, node_stats)
        except BaseException:
            self.backend.close()
            raise

    def _prepare(self, substitutions: dict[str, Any] | None, node_stats: bool) -> None:
        """The robot spawned at the start, the context and the tree built."""
        mission = self.mission
        problem = self.backend.spawn_problem(self.backend.robot_name, mission.start)
        if problem:
            raise UserError(
                Problem(
                    f"impossible start pose: {problem}",
                    *mission.start_where,
                    "start",
                    "pick a free pose inside the maze, e.g. a named spawn of the maze",
                )
            )
        start = self.backend.request_spawn(self.backend.robot_name, mission.start)
        #: why the run cannot start (code, reason): a robot that is not there, a start it was refused
        self.unstarted: tuple[FailureCode, str] | None = None
        #: the node an unstarted run names (one whose constructor raised), if any
        self.unstarted_path: str | None = None
        try:
            self.backend.advance(0.0)
        except RobotLost as exc:
            self.unstarted = (FailureCode.ROBOT_LOST, str(exc))
        if self.unstarted is None and start.state is RequestState.FAILED:
            self.unstarted = (FailureCode.ENTITY_ERROR, f"the robot could not be put at the start: {start.reason}")
        self.period = 1.0 / mission.tick_hz
        self.events = EventLog()
        self.ctx = Context(
            robot=self.backend,
            entities=self.backend,
            events=self.events,
            tick_period=self.period,
            bounds=MazeShapes.of(mission.maze).bounds if mission.maze.walls else None,
            goal=tuple(mission.maze.goal),
            collision_count=lambda: len(self.backend.collisions),
        )
        py_trees.blackboard.Blackboard.clear()
        self.root = self._build(substitutions)
        self.substituted = bool(substitutions)
        #: per-node statistics, kept when ``node_stats`` (every node of the tree counts its ticks)
        self.stats: NodeStats | None = None
        if node_stats:
            from thymio_bt.run.coverage import NodeStats  # its counting (and BT.CPP's node types) only then

            self.stats = NodeStats(self.period)
            self.stats.attach(self.root, self.mission.tree)
        self.ticks = 0
        self._collisions_seen = 0  # collisions that have had their event
        self._final_tree: str | None = ""
        self.trajectory: list[tuple[float, float, float, float]] = []

    def shown_tree(self) -> Behaviour:
        """The tree a recording of this run shows (its nodes and their statuses after each tick): the
        ticked tree itself, unless the tree ticks elsewhere (:class:`thymio_bt.grade.remote_run.RemoteRun`)."""
        return self.root

    def _build(self, substitutions: dict[str, Any] | None) -> Behaviour:
        """The mission's tree; when a node's constructor (a plugin's) raises, a stand-in root that
        fails, and the run is unstarted: it ends at once, FAILURE with code EXCEPTION naming the node."""
        try:
            return build_tree(self.mission.tree, self.ctx, self.mission.registry, substitutions)
        except BaseException as exc:
            if isinstance(exc, UserError) or not is_fault(exc):
                raise
            where = _building_node(exc)
            if self.unstarted is None:
                self.unstarted = (FailureCode.EXCEPTION, f"'{where}' raised {describe(exc)} when it was built")
                self.unstarted_path = where
            return py_trees.behaviours.Failure(name=self.mission.tree.name)

    def run(
        self, on_tick: TickHook | None = None, realtime: float | None = None, interrupts: Interrupts | None = None
    ) -> RunResult:
        """Tick until the tree ends or the time limit; ``realtime`` paces the loop (1.0 = real time).
        A signal noted in ``interrupts`` ends the run at the next tick: FAILURE, code INTERRUPTED.
        The backend is closed (a real robot's motors stopped) however the run ends, even on Ctrl-C."""
        try:
            return self._run(on_tick, realtime, interrupts or Interrupts())
        finally:
            self.backend.close()

    def _run(self, on_tick: TickHook | None, realtime: float | None, interrupts: Interrupts) -> RunResult:
        """The run's named steps: start, tick loop, end of run, result."""
        wall_start = self._start()
        ending = self._unstarted_ending() or self._tick_loop(on_tick, realtime, interrupts, wall_start)
        verdict = self._end_of_run(ending, interrupts)
        return self._result(verdict, time.perf_counter() - wall_start)

    def _start(self) -> float:
        """Record the start pose; the wall clock's time the run starts at."""
        wall_start = time.perf_counter()
        self._record()
        return wall_start

    def _unstarted_ending(self) -> Ending | None:
        """The run's ending before its first tick when the robot could not be started, else None."""
        if self.unstarted is None:
            return None
        code, reason = self.unstarted
        return Ending(EndKind.CRASHED, code, reason, failed_path=self.unstarted_path)

    def _tick_loop(
        self, on_tick: TickHook | None, realtime: float | None, interrupts: Interrupts, wall_start: float
    ) -> Ending:
        """Tick the tree and advance the backend until something ends the run (the time limit at the latest)."""
        limit_ticks = math.ceil(self.mission.time_limit * self.mission.tick_hz - 1e-9)
        # the loop's own bytecode runs once a run, so CPython 3.11 never specialises it (a function's
        # code is specialised after 8 calls): the tick's work is in _tick, called every tick
        one_tick = self._tick
        try:
            for _ in range(self.ticks, limit_ticks):
                ending = one_tick(on_tick, interrupts)
                if ending is not None:
                    return ending
                if realtime:
                    self._pace(realtime, wall_start, interrupts)
        except Interrupted as exc:  # a second signal, or the grace ran out: the tick never ended
            return self._forced_ending(exc)
        return Ending(EndKind.TIMEOUT, FailureCode.TIMEOUT)

    def _tick(self, on_tick: TickHook | None, interrupts: Interrupts) -> Ending | None:
        """One tick of the tree (its nodes count their own ticks when node statistics are kept), then
        what ends the run, in this order: the tick hook, the tree, a signal, the backend failing to
        advance to the next tick. When nothing does, the collisions counted get their events and the
        pose is recorded. One frame a tick: the checks were two more methods, called every tick."""
        # the root's own tick, not BehaviourTree.tick(): that walks the whole tree again after
        # every tick for "full" visitors, which cost ~15 % of a run here and we have none
        # tick(self.root) without its call: the direct tick, without generators where the node kinds allow it
        root = self.root
        TICK_OF[root.__class__](root)
        self.ticks += 1
        if on_tick is not None:
            try:
                on_tick(self)
            except StopRun as stop:
                return Ending(EndKind.STOPPED, FailureCode.STOPPED, str(stop) or "stopped by a tick hook")
        if self.root.status in _ENDED:
            return Ending(EndKind.FINISHED)
        if interrupts.signal:
            return Ending(EndKind.INTERRUPTED, FailureCode.INTERRUPTED)
        backend = self.backend
        try:  # advance by one tick period
            backend.advance(self.period)
        except RobotLost as exc:  # a real robot gone silent: its own code
            return Ending(EndKind.CRASHED, FailureCode.ROBOT_LOST, str(exc))
        except BaseException as exc:  # a backend's bug (a plugin's, say): end the run, say why
            if not is_fault(exc):
                raise
            return Ending(EndKind.CRASHED, FailureCode.BACKEND_ERROR, f"the backend raised {describe(exc)}")
        if len(backend.collisions) > self._collisions_seen or backend.min_clearance <= CONTACT:
            self._collisions_seen = self._emit_collisions(self._collisions_seen)  # rare: a contact
        self._record()
        return None

    def _forced_ending(self, exc: Interrupted) -> Ending:
        """The ending of a run whose tick was broken into (a second signal, or none within the grace
        period of :mod:`~thymio_bt.run.interrupts`): the node whose code was running
        (and its ancestors) marked RUNNING, so that stopping the tree halts it like any running node."""
        stuck = _running_node(exc)
        where = None
        if stuck is not None:
            node: Behaviour | None = stuck
            while node is not None:
                node.status = Status.RUNNING  # it was inside its tick: it had not ended
                node = node.parent
            where = node_path(stuck)
        reason = f"'{where}' never ended its tick; {exc.how}" if where else f"a tick never ended; {exc.how}"
        return Ending(EndKind.INTERRUPTED, FailureCode.INTERRUPTED, reason, failed_path=where, forced=True)

    def _emit_collisions(self, seen: int) -> int:
        """A ``collision`` event for each collision the backend counted past the first ``seen``; how
        many have had their event."""
        self._contact()
        collisions = self.backend.collisions
        if len(collisions) <= seen:
            return seen
        for c in collisions[seen:]:
            self.events.emit(c.t, "collision", x=round(c.x, 6), y=round(c.y, 6))
        return len(collisions)

    def _contact(self) -> None:
        """Contact is a collision: a backend whose clearance reached :data:`CONTACT` but that counted
        no collision (its contact detection missed it, or it has none) gets one, at the robot's pose
        when the runner sees it (at most a tick late), so that behaviours fail with COLLISION, the
        report counts it and ``expect: {no_collision: true}`` fails, on every backend."""
        backend = self.backend
        if backend.collisions or not backend.min_clearance <= CONTACT:
            return
        pose = backend.true_pose() or backend.pose()
        if pose is not None:
            x, y = pose.x, pose.y
        else:
            x, y = self.trajectory[-1][1:3] if self.trajectory else (0.0, 0.0)
        backend.collisions.append(Collision(backend.time(), x, y))

    def _pace(self, realtime: float, wall_start: float, interrupts: Interrupts) -> None:
        """Wait until the wall clock catches up with simulated time / ``realtime`` (``--realtime``), or
        a signal comes: a slow pace (a tick lasting seconds) still ends at once, not broken into."""
        while (lag := self.backend.time() / realtime - (time.perf_counter() - wall_start)) > 0:
            if interrupts.signal:
                return
            time.sleep(min(lag, PACE_SLICE))  # realtime: pacing asked for with --realtime

    def _end_of_run(self, ending: Ending, interrupts: Interrupts) -> RunOutcome:
        """The report's status, reason, code and failing node; a run cut short has its running
        behaviours stopped (their events written, the robot stopped) once the final tree is drawn."""
        self._final_tree = None  # drawn when read (the terminal viewer does)
        if ending.kind is EndKind.FINISHED:
            if self.root.status is Status.FAILURE:
                failed_path, code, reason = failing_branch(self.root)
                return RunOutcome(RunStatus.FAILURE, reason, code, failed_path)
            return RunOutcome(RunStatus.SUCCESS)
        self._final_tree = self.final_tree  # now: stopping the running behaviours changes it
        running = self.root.tip()
        verdict = RunOutcome(
            ending.kind.report_status,
            self._cut_short_reason(ending, interrupts),
            ending.code,
            ending.failed_path or (node_path(running) if running is not None else None),
        )
        self.root.stop(Status.INVALID)  # ends the running behaviours: events, robot stopped
        if ending.forced:
            self._stop_motors()
        return verdict

    def _stop_motors(self) -> None:
        """Stop the robot whatever the tree did (a tick broken into may have left any command)."""
        try:
            if self.backend.exists():
                self.backend.drive(0.0, 0.0)
        except Exception:  # noqa: S110 - a robot already gone is stopped; close() tries again
            pass

    def _cut_short_reason(self, ending: Ending, interrupts: Interrupts) -> str | None:
        """Why a run that the tree did not end was cut short, in the report's words."""
        if ending.kind is EndKind.TIMEOUT:
            return f"time limit of {self.mission.time_limit:g} s reached"
        if ending.kind is EndKind.INTERRUPTED:
            said = f"interrupted by {interrupts.name} at {self.backend.time():.1f} s"
            return f"{said}: {ending.reason}" if ending.reason else said
        return ending.reason

    def _result(self, verdict: RunOutcome, wall: float) -> RunResult:
        """The run's result: the verdict, the robot's final state, events, phases, the learnt map,
        whether it reached the maze's goal and whether the mission's ``expect:`` held."""
        sim = self.backend
        self._contact()
        final = snapshot(sim)
        true_pose = sim.true_pose()
        learnt = learnt_map(self.root)
        result = RunResult(
            mission=self.mission.name,
            maze=self.mission.maze.name,
            status=verdict.status,
            reason=verdict.reason,
            code=verdict.code,
            failed_path=verdict.failed_path,
            sim_time=sim.time(),
            ticks=self.ticks,
            wall_time=wall,
            seed=self.seed,
            final_pose=None if true_pose is None else Pose(*(round(v, 6) for v in true_pose.as_tuple())),
            final_proximity=final["proximity"],
            events=list(self.events),
            collisions=len(sim.collisions),
            min_clearance=None if math.isinf(sim.min_clearance) else sim.min_clearance,
            trajectory=self.trajectory,
            node_stats=self.stats.table if self.stats else None,
            phases=phases(self.mission.tree, self.events),
            maze_map=None if learnt is None else learnt.summary(),
        )
        if self.mission.maze.goal:
            reached = next((t for t, x, y, _ in self.trajectory if self.mission.maze.in_goal(x, y)), None)
            result.goal = GoalReached(reached is not None, reached)
        if self.mission.expect is not None:
            self._check_expectations(result, self.mission.expect, places=not self.substituted)
        return result

    @property
    def final_tree(self) -> str:
        """The tree with each node's status and feedback as the run ended ("" before it runs)."""
        if self._final_tree is None:
            self._final_tree = py_trees.display.unicode_tree(self.root, show_status=True)
        return self._final_tree

    def _check_expectations(self, result: RunResult, expect: Expect, places: bool) -> None:
        """A tree that succeeded without meeting the mission's ``expect:`` makes the run a FAILURE.
        With nodes substituted (a test of part of a mission), where it ends is not checked."""
        from thymio_bt.run.verdict import check

        expect = expect if places else expect.without_places()
        # the robot that ran (a calibrated profile, a backend's own), not only the one the mission names
        result.expectations = check(expect, result, self.mission.maze, self.backend.model)
        if result.status is RunStatus.SUCCESS and result.expectations:
            result.status, result.code, result.failed_path = RunStatus.FAILURE, FailureCode.EXPECTATION, "expect"
            result.reason = "; ".join(result.expectations)

    def _record(self) -> None:
        pose = self.backend.true_pose()
        if pose is not None:
            self.trajectory.append((self.backend.time(), pose.x, pose.y, pose.yaw))


def _running_node(exc: BaseException) -> Behaviour | None:
    """The innermost tree node whose method was running where ``exc`` was raised (None: no node's)."""
    found = None
    tb = exc.__traceback__
    while tb is not None:
        owner = tb.tb_frame.f_locals.get("self")
        if isinstance(owner, Behaviour):
            found = owner
        tb = tb.tb_next
    return found


def _building_node(exc: BaseException) -> str:
    """The path of the node whose construction raised ``exc`` (the innermost ``build_tree`` call's)."""
    where = "the tree"
    tb = exc.__traceback__
    while tb is not None:
        frame = tb.tb_frame
        if frame.f_code.co_name == "build_tree" and isinstance(frame.f_locals.get("path"), str):
            where = frame.f_locals["path"]
        tb = tb.tb_next
    return where


def run_mission(mission: Mission, seed: int | None = None, **kwargs: Any) -> RunResult:
    """Build and run ``mission`` once."""
    return Run(mission, seed).run(**kwargs)


__all__ = ["CONTACT", "Run", "RunResult", "RunStatus", "TickHook", "run_mission"]
