"""One student's runs, in the child process :mod:`.isolation` forked for them: every world of the
assignment with each of its seeds, each run judged by every criterion that applies to its world.

The messages sent back are small: the run's outcome, each criterion's judgement, the node
statistics (for coverage) and, for the first seed of each world, the trajectory (for pictures).

Example (in this process; the grader runs it in a child)::

    >>> from pathlib import Path
    >>> from thymio_bt.grade.assignment import Criterion, Variant
    >>> variant = Variant(name="course", maze="two_parts_maze", start="part1", noise="off")
    >>> world = World.of(variant, Path("."), Path("."))
    >>> task = StudentTask("ada", "missions/maze_part1_2.yaml", [world], [
    ...     Criterion(name="stops 5 cm from the wall", points=2, gap={"at": "delete", "distance": "5cm"})])
    >>> messages = []
    >>> grade_runs(task, messages.append)
    >>> run = messages[-1]
    >>> run["variant"], run["status"], run["criteria"]["stops 5 cm from the wall"], len(run["trajectory"]) > 10
    ('course', <RunStatus.SUCCESS: 'SUCCESS'>, {'passed': True, 'feedback': None, 'moment': None, 'where': None}, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from thymio_bt.behaviours.base import FailureCode
from thymio_bt.errors import ThymioBtError, UserError
from thymio_bt.grade.assignment import Criterion
from thymio_bt.grade.checks import Judgement, RunFacts, judge
from thymio_bt.grade.isolation import Limits, RunLimit, Send, run_limited
from thymio_bt.grade.palette import wheres
from thymio_bt.grade.site_replay import replay_data, went_wrong
from thymio_bt.grade.worlds import World
from thymio_bt.run.result import RunResult, RunStatus

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording
    from thymio_bt.mission import Mission

#: the most trajectory samples a run sends (for its picture)
PICTURE_SAMPLES = 300


@dataclass
class StudentTask:
    """Everything a child needs to run one student's submission (picklable: also a Dask task)."""

    name: str
    file: str
    worlds: list[World]
    criteria: list[Criterion]
    run_plugins: bool = True
    limits: Limits | None = None
    time_limit: float | None = None
    #: run the tree in a confined process of its own (:mod:`.sandbox`): a submission with plugins
    sandboxed: bool = False
    #: the student's folder (copied for the confined process), None for a lone mission file
    home: str | None = None
    #: the variants whose first failed run of each mistake is recorded for its replay (``grade --html``)
    replays: list[str] = field(default_factory=list)

    @property
    def runs(self) -> int:
        """How many runs the submission makes."""
        return sum(len(w.seeds) for w in self.worlds)

    def plan(self) -> list[tuple[World, int]]:
        """Each run's world and seed, in order."""
        return [(world, seed) for world in self.worlds for seed in world.seeds]


def grade_runs(task: StudentTask, send: Send, skip: int = 0) -> None:
    """Run ``task``'s runs but the first ``skip``, sending a ``start`` then a ``run`` message each.
    Once :data:`OVERRUNS` runs went over a time limit (wall-clock or CPU), the others fail at once."""
    missions: dict[str, Mission | str] = {}
    pictured: set[str] = set()
    replayed: set[tuple[str, str]] = set()  # (variant, what went wrong) with a replay already
    overran: list[dict[str, Any]] = []
    outside = _Outside(task)
    try:
        for index, (world, seed) in enumerate(task.plan()):
            if index < skip:
                pictured.add(world.name)
                continue
            send({"kind": "start", "index": index})
            if world.name not in missions:
                try:
                    plugins = task.run_plugins and not task.sandboxed
                    missions[world.name] = world.mission(task.file, plugins, task.time_limit)
                except UserError as exc:
                    missions[world.name] = f"the mission cannot run in this world: {exc}"
            mission = missions[world.name]
            picture = world.name not in pictured
            pictured.add(world.name)
            if len(overran) >= OVERRUNS:
                message = _skipped(task, index, world, seed, overran)
            else:
                message = run_message(task, index, world, seed, mission, picture, outside, replayed)
                if message.get("code") == "LIMIT" and "time limit" in str(message.get("reason")):
                    overran.append(message)
            send(message)
    finally:
        outside.close()


#: how many runs of a student may go over the wall-clock limit before the rest are skipped
OVERRUNS = 2


def _skipped(task: StudentTask, index: int, world: World, seed: int, overran: list[dict[str, Any]]) -> dict[str, Any]:
    """A run not made: the student's runs already went over the time limit :data:`OVERRUNS` times."""
    criteria = [c for c in task.criteria if c.variants is None or world.name in c.variants]
    head = {"kind": "run", "index": index, "variant": world.name, "seed": seed, "robot": world.robot}
    said = "; ".join(f"run {m['index'] + 1}: {m['reason']}" for m in overran)
    return head | _broken("LIMIT", f"skipped: {len(overran)} runs went over the time limit ({said})", criteria)


class _Outside:
    """The confined process a sandboxed student's runs tick their tree in (one at a time: a run
    that broke it, by a limit or a fault, is followed by a fresh one)."""

    def __init__(self, task: StudentTask) -> None:
        self.task = task
        self.sandbox: Any = None

    def get(self, mission: Mission) -> Any:
        """The process, started if need be."""
        from thymio_bt.grade.sandboxes import Sandbox

        if self.sandbox is None:
            limits = self.task.limits or Limits()
            home = Path(self.task.home) if self.task.home else None
            cpu = int(limits.cpu * self.task.runs + 30)
            self.sandbox = Sandbox.open(Path(self.task.file), home, list(mission.sources), limits.memory_mib << 20, cpu)
        return self.sandbox

    def close(self) -> None:
        """End the process (and all it started)."""
        if self.sandbox is not None:
            self.sandbox.close()
            self.sandbox = None


def run_message(
    task: StudentTask,
    index: int,
    world: World,
    seed: int,
    mission: Mission | str,
    picture: bool,
    outside: _Outside | None = None,
    replayed: set[tuple[str, str]] | None = None,
) -> dict[str, Any]:
    """Run ``mission`` in ``world`` with ``seed`` and judge it: the ``run`` message. A run of a world
    of the task's ``replays`` that makes a mistake not yet in ``replayed`` carries its ``replay``
    (:mod:`.site_replay`)."""
    head: dict[str, Any] = {"kind": "run", "index": index, "variant": world.name, "seed": seed, "robot": world.robot}
    criteria = [c for c in task.criteria if c.variants is None or world.name in c.variants]
    if isinstance(mission, str):
        return head | _broken("WORLD_ERROR", mission, criteria)
    try:
        result = _graded_run(task, mission, seed, world, outside)
    except _Broken as exc:
        return head | _broken(exc.code, exc.reason, criteria)
    message = head | _judged(mission, world, result, criteria)
    new = {(world.name, what) for what in went_wrong(message)} - (replayed or set())
    if replayed is not None and world.name in task.replays and new:
        recording = _recorded(task, mission, seed, world, outside, result)
        if recording is not None:
            message["replay"] = replay_data(recording, message)
            replayed |= new
    if picture:
        message["trajectory"] = _picture(result.trajectory)
    return message


def _run(
    task: StudentTask, mission: Mission, seed: int, world: World, outside: _Outside | None, recorder: Any = None
) -> Any:
    """The run, within the task's limits: its tree in the submission's confined process when the task
    is sandboxed, else here."""
    from thymio_bt.run.runner import Run

    limits = task.limits or Limits()
    if task.sandboxed and outside is not None:
        return _outside_run(outside, mission, seed, limits, world, recorder)
    return run_limited(limits, lambda: Run(mission, seed, node_stats=True).run(on_tick=recorder))


def _graded_run(task: StudentTask, mission: Mission, seed: int, world: World, outside: _Outside | None) -> Any:
    """The graded run's result; a run that broke (a limit, a crash, an exception, a world it cannot
    run in) raises :class:`_Broken` with its code and reason."""
    try:
        return _run(task, mission, seed, world, outside)
    except RunLimit as exc:
        _close(outside)
        raise _Broken("LIMIT", str(exc)) from None
    except _Broken:
        _close(outside)
        raise
    except MemoryError:
        memory = (task.limits or Limits()).memory_mib
        raise _Broken("LIMIT", f"the run used more than its memory ({memory} MiB)") from None
    except UserError as exc:
        raise _Broken("WORLD_ERROR", f"the mission cannot run in this world: {exc}") from None
    except SystemExit as exc:
        raise _Broken(FailureCode.EXCEPTION, f"the submission called sys.exit({exc.code!r})") from None
    except Exception as exc:
        raise _Broken(FailureCode.EXCEPTION, f"the run raised {type(exc).__name__}: {exc}") from None


def _close(outside: _Outside | None) -> None:
    """End the submission's confined process, if any (after a run that broke it)."""
    if outside is not None:
        outside.close()


def _judged(mission: Mission, world: World, result: Any, criteria: list[Criterion]) -> dict[str, Any]:
    """The run message's outcome of a run that ended: how it ended, and each criterion's judgement."""
    from thymio_bt.robot.model import robot_model

    places = wheres(mission.tree)
    facts = RunFacts(
        result, mission.maze, robot_model(mission.robot), mission.time_limit, world.goal, world.turns, world.cell
    )
    return {
        "status": result.status,
        "code": result.code,
        "reason": result.reason,
        "failed_path": result.failed_path,
        "where": places.get(result.failed_path or ""),
        "sim_time": round(result.sim_time, 3),
        "final_pose": result.final_pose_json,
        "collisions": result.collisions,
        "spawns": [e["t"] for e in result.events if e["kind"] == "spawn_entity"],  # the path's jumps
        "criteria": {c.name: _judgement(judge(c, facts), places) for c in criteria},
        "node_stats": _rows(result.node_stats),
    }


def _picture(trajectory: list[tuple[float, float, float, float]]) -> list[list[float]]:
    """At most :data:`PICTURE_SAMPLES` of the trajectory's samples and its last, to 4 decimals."""
    step = max(1, len(trajectory) // PICTURE_SAMPLES + 1)
    samples = trajectory[::step] + trajectory[-1:]
    return [[round(v, 4) for v in sample] for sample in samples]


def _recorded(
    task: StudentTask, mission: Mission, seed: int, world: World, outside: _Outside | None, result: RunResult
) -> Recording | None:
    """The run made again the same way (a confined tree in its confined process), recorded for its
    replay: runs are deterministic, so only the runs that get a page pay for a recording. None when
    the run did not end as ``result`` did (a submission that is not deterministic) or broke."""
    from thymio_bt.logs.recording import Recorder

    recorder = Recorder(statuses=True)
    try:
        again = _run(task, mission, seed, world, outside, recorder)
    except Exception:  # a limit, a crash: no replay (the graded run's message says what it did)
        _close(outside)
        return None
    ended = (again.status, again.code, again.sim_time, again.final_pose)
    return recorder.finish(again) if ended == (result.status, result.code, result.sim_time, result.final_pose) else None


class _Broken(ThymioBtError):
    """A run the submission's process broke: its code and reason."""

    def __init__(self, code: FailureCode | str, reason: str) -> None:
        super().__init__(reason)
        self.code, self.reason = code, reason


def _outside_run(
    outside: _Outside, mission: Mission, seed: int, limits: Limits, world: World, recorder: Any = None
) -> Any:
    """The run with its tree in the submission's confined process (:mod:`.remote_run`)."""
    from thymio_bt.grade.remote_run import RemoteRun, SubmissionFault
    from thymio_bt.grade.wire import WireError

    try:
        sandbox = outside.get(mission)
    except (WireError, OSError) as exc:
        raise _Broken("CRASH", f"the submission's process could not start: {exc}") from None
    if sandbox.error:
        raise _Broken("CRASH", sandbox.error)
    home = Path(outside.task.home) if outside.task.home else None
    spec = {
        "mission": {
            "path": str(sandbox.copy_of(Path(outside.task.file), home)),
            "overrides": {**world.settings, "time_limit": f"{mission.time_limit:g}"},
            "maze": sandbox.maze_file(mission.maze),
            "start": world.start,
        },
        "period": 1.0 / mission.tick_hz,
        "bounds": list(mission.maze.bounds()) if mission.maze.walls else None,
        "goal": [
            [min(a.start[0], a.end[0]), min(a.start[1], a.end[1]), max(a.start[0], a.end[0]), max(a.start[1], a.end[1])]
            for a in mission.maze.goal
        ],
    }
    try:
        result = RemoteRun(mission, seed, sandbox, limits, spec).run(on_tick=recorder)
        sandbox.end_run()  # what the run started ends with it
        return result
    except SubmissionFault as exc:
        raise _Broken(FailureCode.EXCEPTION, str(exc)) from None
    except WireError as exc:
        said = f"os._exit, a crash, or its memory limit of {limits.memory_mib} MiB"
        raise _Broken("CRASH", f"{exc} during the run ({said})") from None


def _rows(stats: dict[str, dict[str, float]] | None) -> dict[str, Any]:
    """The run's node statistics as JSON can carry them (with each composite's ``ended_by``)."""
    from thymio_bt.run.coverage import NodeTable

    return stats.rows() if isinstance(stats, NodeTable) else dict(stats or {})


def _judgement(judgement: Judgement, places: dict[str, str | None]) -> dict[str, Any]:
    return {
        "passed": judgement.passed,
        "feedback": judgement.feedback,
        "moment": judgement.moment,
        "where": places.get(judgement.path or ""),
    }


def _broken(code: FailureCode | str, reason: str, criteria: list[Criterion]) -> dict[str, Any]:
    """A run that could not run or was stopped: every criterion fails with its reason (``code``: the
    run's :class:`FailureCode`, or the grader's own ``LIMIT``, ``CRASH``, ``WORLD_ERROR``)."""
    judged = {c.name: {"passed": False, "feedback": reason, "moment": None, "where": None} for c in criteria}
    return {
        "status": RunStatus.FAILURE,
        "code": code,
        "reason": reason,
        "failed_path": None,
        "where": None,
        "sim_time": 0.0,
        "final_pose": None,
        "collisions": 0,
        "criteria": judged,
        "node_stats": {},
    }


def died_message(task: StudentTask, message: dict[str, Any]) -> dict[str, Any]:
    """The ``run`` message of a run whose process died (a :mod:`.isolation` ``died`` message)."""
    world, seed = task.plan()[message["index"]]
    criteria = [c for c in task.criteria if c.variants is None or world.name in c.variants]
    head = {"kind": "run", "index": message["index"], "variant": world.name, "seed": seed, "robot": world.robot}
    return head | _broken("CRASH", message["reason"], criteria)


__all__ = ["StudentTask", "died_message", "grade_runs", "run_message"]
