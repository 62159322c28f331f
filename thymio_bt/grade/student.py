"""One student's runs, in the child process :mod:`.isolation` forked for them: every world of the
assignment with each of its seeds, each run judged by every criterion that applies to its world.

The messages sent back are small: the run's outcome, each criterion's judgement, the node
statistics (for coverage) and, for the first seed of each world, the trajectory (for pictures):
a :class:`~.results.RunMessage` as JSON, read back in the grader by :func:`read_message`.

Example (in this process; the grader runs it in a child)::

    >>> from pathlib import Path
    >>> from thymio_bt.grade.assignment import Criterion, Variant
    >>> variant = Variant(name="course", maze="two_parts_maze", start="part1", noise="off")
    >>> world = World.of(variant, Path("."), Path("."))
    >>> task = StudentTask("ada", "missions/maze_part1_2.yaml", [world], [
    ...     Criterion(name="stops 5 cm from the wall", points=2, gap={"at": "delete", "distance": "5cm"})])
    >>> messages = []
    >>> grade_runs(task, messages.append)
    >>> run = read_message(task, messages[-1])
    >>> run.variant, run.status, run.criteria["stops 5 cm from the wall"], len(run.trajectory or []) > 10
    ('course', <RunStatus.SUCCESS: 'SUCCESS'>, Judged(passed=True, feedback=None, moment=None, where=None), True)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from thymio_bt.enums import FailureCode
from thymio_bt.errors import ThymioBtError, UserError
from thymio_bt.grade.assignment import Criterion
from thymio_bt.grade.checks import Judgement, RunFacts, judge
from thymio_bt.grade.isolation import Limits, RunLimit, Send, run_limited
from thymio_bt.grade.palette import wheres
from thymio_bt.grade.results import GraderCode, Judged, RunCode, RunMessage
from thymio_bt.grade.site_replay import replay_data, went_wrong
from thymio_bt.grade.worlds import World
from thymio_bt.run.result import RunResult, RunStatus

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording
    from thymio_bt.plan.model import Mission

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

    def criteria_of(self, world: World) -> list[Criterion]:
        """The criteria that judge the runs of ``world``."""
        return [c for c in self.criteria if c.variants is None or world.name in c.variants]


def grade_runs(task: StudentTask, send: Send, skip: int = 0) -> None:
    """Run ``task``'s runs but the first ``skip``, sending a ``start`` then a ``run`` message each.
    Once :data:`OVERRUNS` runs went over a time limit (wall-clock or CPU), the others fail at once."""
    missions: dict[str, Mission | str] = {}
    pictured: set[str] = set()
    replayed: set[tuple[str, str]] = set()  # (variant, what went wrong) with a replay already
    overran: list[RunMessage] = []
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
                if message.code == GraderCode.LIMIT and "time limit" in (message.reason or ""):
                    overran.append(message)
            send({"kind": "run", **message.to_json()})
    finally:
        outside.close()


#: how many runs of a student may go over the wall-clock limit before the rest are skipped
OVERRUNS = 2


def _skipped(task: StudentTask, index: int, world: World, seed: int, overran: list[RunMessage]) -> RunMessage:
    """A run not made: the student's runs already went over the time limit :data:`OVERRUNS` times."""
    said = "; ".join(f"run {m.index + 1}: {m.reason}" for m in overran)
    reason = f"skipped: {len(overran)} runs went over the time limit ({said})"
    return _broken(task, index, world, seed, GraderCode.LIMIT, reason)


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
) -> RunMessage:
    """Run ``mission`` in ``world`` with ``seed`` and judge it: the ``run`` message. A run of a world
    of the task's ``replays`` that makes a mistake not yet in ``replayed`` carries its ``replay``
    (:mod:`.site_replay`)."""
    if isinstance(mission, str):
        return _broken(task, index, world, seed, GraderCode.WORLD_ERROR, mission)
    try:
        result = _graded_run(task, mission, seed, world, outside)
    except _Broken as exc:
        return _broken(task, index, world, seed, exc.code, exc.reason)
    message = _judged(task, index, world, seed, mission, result)
    new = {(world.name, what) for what in went_wrong(message)} - (replayed or set())
    if replayed is not None and world.name in task.replays and new:
        recording = _recorded(task, mission, seed, world, outside, result)
        if recording is not None:
            message.replay = replay_data(recording, message)
            replayed |= new
    if picture:
        message.trajectory = _picture(result.trajectory)
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
        raise _Broken(GraderCode.LIMIT, str(exc)) from None
    except _Broken:
        _close(outside)
        raise
    except MemoryError:
        memory = (task.limits or Limits()).memory_mib
        raise _Broken(GraderCode.LIMIT, f"the run used more than its memory ({memory} MiB)") from None
    except UserError as exc:
        raise _Broken(GraderCode.WORLD_ERROR, f"the mission cannot run in this world: {exc}") from None
    except SystemExit as exc:
        raise _Broken(FailureCode.EXCEPTION, f"the submission called sys.exit({exc.code!r})") from None
    except Exception as exc:
        raise _Broken(FailureCode.EXCEPTION, f"the run raised {type(exc).__name__}: {exc}") from None


def _close(outside: _Outside | None) -> None:
    """End the submission's confined process, if any (after a run that broke it)."""
    if outside is not None:
        outside.close()


def _judged(task: StudentTask, index: int, world: World, seed: int, mission: Mission, result: RunResult) -> RunMessage:
    """The run message of a run that ended: how it ended, and each criterion's judgement."""
    from thymio_bt.robot.model import robot_model

    places = wheres(mission.tree)
    facts = RunFacts(
        result, mission.maze, robot_model(mission.robot), mission.time_limit, world.goal, world.turns, world.cell
    )
    return RunMessage(
        index=index,
        variant=world.name,
        seed=seed,
        robot=world.robot,
        status=result.status,
        code=result.code,
        reason=result.reason,
        failed_path=result.failed_path,
        where=places.get(result.failed_path or ""),
        sim_time=round(result.sim_time, 3),
        final_pose=result.final_pose_json,
        collisions=result.collisions,
        spawns=[e["t"] for e in result.events if e["kind"] == "spawn_entity"],  # the path's jumps
        criteria={c.name: _judgement(judge(c, facts), places) for c in task.criteria_of(world)},
        node_stats=_rows(result.node_stats),
    )


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

    def __init__(self, code: RunCode, reason: str) -> None:
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
        raise _Broken(GraderCode.CRASH, f"the submission's process could not start: {exc}") from None
    if sandbox.error:
        raise _Broken(GraderCode.CRASH, sandbox.error)
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
        "goal": [area.model_dump(mode="json", by_alias=True) for area in mission.maze.goal],
    }
    try:
        result = RemoteRun(mission, seed, sandbox, limits, spec).run(on_tick=recorder)
        sandbox.end_run()  # what the run started ends with it
        return result
    except SubmissionFault as exc:
        raise _Broken(FailureCode.EXCEPTION, str(exc)) from None
    except WireError as exc:
        said = f"os._exit, a crash, or its memory limit of {limits.memory_mib} MiB"
        raise _Broken(GraderCode.CRASH, f"{exc} during the run ({said})") from None


def _rows(stats: dict[str, dict[str, float]] | None) -> dict[str, Any]:
    """The run's node statistics as JSON can carry them (with each composite's ``ended_by``)."""
    from thymio_bt.run.coverage import NodeTable

    return stats.rows() if isinstance(stats, NodeTable) else dict(stats or {})


def _judgement(judgement: Judgement, places: dict[str, str | None]) -> Judged:
    return Judged(
        passed=judgement.passed,
        feedback=judgement.feedback,
        moment=judgement.moment,
        where=places.get(judgement.path or ""),
    )


def _broken(task: StudentTask, index: int, world: World, seed: int, code: RunCode, reason: str) -> RunMessage:
    """A run that could not run or was stopped: every criterion fails with its reason (``code``: the
    run's :class:`FailureCode`, or the grader's own :class:`~.results.GraderCode`)."""
    return RunMessage(
        index=index,
        variant=world.name,
        seed=seed,
        robot=world.robot,
        status=RunStatus.FAILURE,
        code=code,
        reason=reason,
        criteria={c.name: Judged(passed=False, feedback=reason) for c in task.criteria_of(world)},
    )


def died_message(task: StudentTask, index: int, reason: str) -> RunMessage:
    """The ``run`` message of the run ``index`` whose process died (a :mod:`.isolation` ``died`` message)."""
    world, seed = task.plan()[index]
    return _broken(task, index, world, seed, GraderCode.CRASH, reason)


def read_message(task: StudentTask, message: dict[str, Any]) -> RunMessage:
    """A run's message from the child process that made it (JSON, through a pipe), checked: a ``died``
    message is the run's crash; a ``run`` message must be the contract's and name a run of the task,
    with the judgement of each of its world's criteria and nothing else. A message that is not is
    the run's crash too, never an error of the grader nor a judgement the grader did not make."""
    plan = task.plan()
    if not isinstance(message, dict):
        return died_message(task, 0, "the run's process sent what no run sends (not a JSON object)")
    index = message.get("index")
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(plan):
        index = 0
    if message.get("kind") == "died":
        return died_message(task, index, str(message.get("reason")))
    world, seed = plan[index]
    try:
        run = RunMessage.from_json({k: v for k, v in message.items() if k != "kind"})
    except ValueError as exc:
        return died_message(task, index, f"the run's process sent what no run sends ({exc})")
    wanted = {c.name for c in task.criteria_of(world)}
    if message.get("kind") != "run" or (run.variant, run.seed, run.robot) != (world.name, seed, world.robot):
        return died_message(task, index, "the run's process sent a run of another world or seed")
    if set(run.criteria) != wanted:
        return died_message(task, index, "the run's process sent judgements of other criteria")
    return run


__all__ = ["StudentTask", "died_message", "grade_runs", "read_message", "run_message"]
