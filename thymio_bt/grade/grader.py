"""Grade a class: every submission in every world of the assignment, scored on its criteria.

The grader reads each submission without running its code (its plan, its palette), then runs it
in child processes of its own (:mod:`.isolation`), locally or on a Dask cluster, and scores each
criterion on the share of its runs that passed. It writes nothing itself: :func:`grade` returns
the results (the ``results.json`` contract of docs/grading.md).

Example::

    >>> results = grade("assignments/course_part1_2.yaml", ["examples/class/ada", "examples/class/chen"])
    >>> [(s["name"], s["status"], s["score"], s["max"]) for s in results["students"]]
    [('ada', 'graded', 11.0, 11.0), ('chen', 'graded', 2.0, 11.0)]
    >>> [p["message"] for p in results["students"][1]["palette"]], results["summary"]["runs"]
    (['WallFollow is not allowed in this assignment'], 24)
"""

from __future__ import annotations

import contextlib
import os
import shlex
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from thymio_bt.errors import UserError
from thymio_bt.grade.assignment import Assignment, Criterion, resolve_assignment
from thymio_bt.grade.isolation import ForkPool, Limits
from thymio_bt.grade.palette import Finding, check_palette
from thymio_bt.grade.redact import feedback_line
from thymio_bt.grade.similarity import similar_groups, tree_shape
from thymio_bt.grade.student import StudentTask, died_message, grade_runs
from thymio_bt.grade.submissions import Submission, find_submissions
from thymio_bt.grade.worlds import World, load_worlds

#: called with (student, message) as each run ends, in the grader's process
Progress = Callable[[str, dict[str, Any]], None]


@dataclass
class Entry:
    """One student as the grader goes: their submission, the plan read from it, their runs."""

    submission: Submission
    status: str = "graded"
    messages: list[str] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    plan: Any = None
    task: StudentTask | None = None
    runs: list[dict[str, Any]] = field(default_factory=list)


def grade(
    assignment_file: str | Path,
    submissions: Sequence[str | Path],
    workers: int = 2,
    worlds: Path | None = None,
    executor: Any = None,
    progress: Progress | None = None,
    stop: Callable[[], bool] = lambda: False,
    started: Callable[[dict[str, int]], None] | None = None,
    secret: str | None = None,
    select: Callable[[list[World]], list[World]] | None = None,
    relative_to: Path | None = None,
    hidden_worlds: Path | None = None,
    sandbox: str = "plugins",
    replays: str | None = None,
) -> dict[str, Any]:
    """Grade ``submissions`` (files or folders) on the assignment; the results as JSON data.
    Generated mazes go to ``worlds`` (a new temporary folder when None). ``executor``: an object
    with ``imap_unordered`` (:class:`~thymio_bt.run.distributed.DaskExecutor`) to run the
    students on a cluster instead of ``workers`` local processes. ``started`` is told how many
    runs each student will make, once the submissions are read; ``progress`` hears each run end.
    ``secret``: the course's, for generated worlds with a secret seed; ``select``: the worlds to run
    (all when None); ``relative_to``: the folder the results go to, which the commands reproducing
    runs are relative to (the current one when None); ``hidden_worlds``: where the hidden
    variants' mazes go instead of ``worlds`` (out of a site students see).
    ``sandbox``: whose trees tick in a confined process of their own (:mod:`.sandbox`): those of
    submissions with plugins (``plugins``), or every one (``always``: slower, for measurements).
    ``replays``: record the failed runs the site replays (:mod:`.site_replay`) of every variant
    (``all``), of the public ones (``public``: a site for students), or none (None)."""
    began = time.perf_counter()
    path = resolve_assignment(assignment_file)
    folder = worlds or Path(tempfile.mkdtemp(prefix="thymio-bt-worlds-"))
    assignment, made = load_worlds(path, folder, secret, hidden_worlds)
    if select is not None:
        made = select(made)
    entries = [_read(s, assignment, made) for s in find_submissions(submissions, assignment.submission)]
    tasks = [e.task for e in entries if e.task is not None]
    replayed = _replayed(made, replays)
    for each in tasks:
        each.sandboxed = each.sandboxed or (sandbox == "always" and each.run_plugins)
        each.replays = list(replayed)
    by_name = {e.submission.name: e for e in entries}
    if started is not None:
        started({t.name: t.runs for t in tasks})

    def heard(task: StudentTask, message: dict[str, Any]) -> None:
        if message["kind"] == "died":
            message = died_message(task, message)
        by_name[task.name].runs.append(message)
        if progress is not None:
            progress(task.name, message)

    if executor is None:
        _run_here(tasks, workers, _limits(assignment), heard, stop)
    else:
        _run_on_cluster(executor, tasks, heard, stop)
    if stop():  # a signal: the students whose runs were not all made say so
        _interrupted(entries)
    return results(assignment, path, made, entries, time.perf_counter() - began, relative_to)


def _replayed(worlds: list[World], replays: str | None) -> list[str]:
    """The variants whose failed runs are recorded for the site's replays (see :func:`grade`)."""
    return [w.name for w in worlds if replays == "all" or (replays == "public" and w.visibility == "public")]


def _run_here(
    tasks: list[StudentTask],
    workers: int,
    limits: Limits,
    heard: Callable[[StudentTask, dict[str, Any]], None],
    stop: Callable[[], bool],
) -> None:
    """The students' runs in ``workers`` child processes of this machine, forked warm."""
    _warm()
    sandboxed = any(t.sandboxed for t in tasks)
    # a confined student is two processes that take turns (the simulation, its tree): twice as
    # many at once keep the cores busy while each waits for the other
    parallel = 2 * workers if sandboxed else workers
    with _zygote(sandboxed):
        ForkPool[StudentTask](parallel, limits, progress=heard, stop=stop).run(tasks, grade_runs, lambda t: t.runs)


def _run_on_cluster(
    executor: Any,
    tasks: list[StudentTask],
    heard: Callable[[StudentTask, dict[str, Any]], None],
    stop: Callable[[], bool],
) -> None:
    """The students' runs on a cluster (``executor``), each student's messages heard as it ends."""
    by_name = {t.name: t for t in tasks}
    for name, messages in executor.imap_unordered(graded_remotely, tasks):
        for message in messages:
            heard(by_name[name], message)
        if stop():
            break


def _interrupted(entries: list[Entry]) -> None:
    """After a signal: the students graded whose runs were not all made are ``interrupted``."""
    for entry in entries:
        if entry.task is not None and len(entry.runs) < entry.task.runs and entry.status == "graded":
            entry.status = "interrupted"
            entry.messages.append(f"interrupted after {len(entry.runs)} of {entry.task.runs} runs")


def _warm() -> None:
    """Before the children are forked, import and run once what every run needs (a shipped
    mission, no student's code): each child inherits it warm instead of paying for it again
    (0.1 s of a student's 0.5 s)."""
    from thymio_bt.mission import default_registry, load_mission
    from thymio_bt.run.runner import Run

    Run(load_mission("maze_part1_2"), node_stats=True).run()
    default_registry().import_all()  # a student's mission may name any node


def graded_remotely(task: StudentTask) -> tuple[str, list[dict[str, Any]]]:
    """One student's runs on a cluster's worker (still in a child process under the limits)."""
    from thymio_bt.grade.sandboxes import ZYGOTE

    limits = task.limits or Limits()
    if task.sandboxed:  # one zygote for the worker's tasks, its threads' too
        ZYGOTE.ensure()
    ((_, messages),) = ForkPool[StudentTask](1, limits).run([task], grade_runs, lambda t: t.runs)
    return task.name, messages


@contextlib.contextmanager
def _zygote(needed: bool) -> Iterator[None]:
    """The process that starts submissions' confined processes, while the workers run (if needed)."""
    from thymio_bt.grade.reaping import remove_cgroups_of, set_subreaper
    from thymio_bt.grade.sandboxes import ZYGOTE

    if not needed:
        yield
        return
    set_subreaper()  # what a worker's submission leaves behind stays beneath the grader
    try:
        with ZYGOTE:
            yield
    finally:  # the workers' cgroups, once the zygote has ended every process (a signal stops workers early)
        remove_cgroups_of(os.getpid())


def _limits(assignment: Assignment) -> Limits:
    limits = assignment.limits
    return Limits(cpu=limits.cpu, memory_mib=round(limits.memory), wall=limits.wall or 3 * limits.cpu + 5)


def _read(submission: Submission, assignment: Assignment, worlds: list[World]) -> Entry:
    """Read a submission without running any of its code: invalid, or ready to run."""
    from thymio_bt.mission import load_mission

    entry = Entry(submission)
    if submission.file is None:
        entry.status, entry.messages = "invalid", [submission.problem or "nothing handed in"]
        return entry
    try:
        mission = load_mission(submission.file, run_plugins=False)
    except UserError as exc:
        entry.status, entry.messages = "invalid", [str(p) for p in exc.problems]
        return entry
    entry.plan = mission.tree
    entry.findings = check_palette(mission, assignment.palette)
    if any(f.rule == "plugins" for f in entry.findings):
        entry.status = "invalid"
        entry.messages = [f"{f.where}: {f.message}" for f in entry.findings if f.rule == "plugins"]
        return entry
    entry.task = StudentTask(
        submission.name,
        str(submission.file),
        worlds,
        assignment.criteria,
        run_plugins=assignment.palette.plugins,
        limits=_limits(assignment),
        time_limit=assignment.time_limit,
        sandboxed=assignment.palette.plugins and _has_plugins(mission),
        home=str(submission.folder) if submission.folder else None,
    )
    return entry


def _confinement(assignment: Assignment, entries: list[Entry]) -> str:
    """What held around the students' code, for the summary (see :mod:`.confine`)."""
    from thymio_bt.grade.confine import plan

    if not assignment.palette.plugins:
        return "nothing to confine: the assignment allows no plugins (a YAML tree runs no student code)"
    if not any(e.task is not None and e.task.sandboxed for e in entries):
        return "nothing to confine: no submission brings plugins"
    return plan().summary()


def _has_plugins(mission: Any) -> bool:
    """Whether a mission (read without running its plugins) names any plugin: its tree's code is then
    the student's, run in a confined process of its own."""
    from thymio_bt.plan.unrun_plugins import UncheckedParams

    stand_ins = any(cls.Params is UncheckedParams for _, cls in mission.registry.items())
    return stand_ins or any(p.suffix == ".py" for p in mission.sources)


def results(
    assignment: Assignment,
    path: Path,
    worlds: list[World],
    entries: list[Entry],
    wall: float,
    relative_to: Path | None = None,
    hidden_worlds: Path | None = None,
) -> dict[str, Any]:
    """The results.json data."""
    commands = Commands(assignment, path, relative_to)
    students = [_student(assignment, worlds, e, commands) for e in entries]
    return {
        "assignment": {
            "name": assignment.name,
            "title": assignment.title,
            "file": str(path),
            "max": assignment.max_points,
            "criteria": [
                {
                    "name": c.name,
                    "points": c.points,
                    "variants": c.variants or [w.name for w in worlds],
                    "pass_rate": c.pass_rate,
                    "credit": c.credit,
                    "check": c.check,
                }
                for c in assignment.criteria
            ],
            "palette": assignment.palette.model_dump(),
            "variants": [
                {
                    "name": w.name,
                    "maze": str(w.maze_file) if w.maze_file else None,
                    "start": w.start,
                    "robot": w.robot,
                    "seeds": w.seeds,
                    "noise": w.settings.get("noise.wheel", "0") != "0",
                    "visibility": w.visibility,
                }
                for w in worlds
            ],
        },
        "students": students,
        "summary": summary(students, [c.name for c in assignment.criteria], wall)
        | {"confinement": _confinement(assignment, entries)},
        "similar": similar_groups(students),
    }


#: a student's ``status`` in results.json, each counted in its summary
STATUSES = ("graded", "invalid", "error", "interrupted")


def summary(students: list[dict[str, Any]], criteria: list[str], wall: float) -> dict[str, Any]:
    """results.json's ``summary`` of ``students``: counts, runs, the mean score, each criterion's
    pass rate over the graded students."""
    graded = [s for s in students if s["status"] == "graded"]
    return {
        "students": len(students),
        **{status: sum(s["status"] == status for s in students) for status in STATUSES},
        "runs": sum(len(s["runs"]) for s in students),
        "wall_time": round(wall, 3),
        "mean_score": round(sum(s["score"] for s in students) / len(students), 3) if students else None,
        "criteria": [
            {
                "name": name,
                "pass_rate": round(
                    sum(sc["passed"] for s in graded for sc in s["criteria"] if sc["name"] == name) / len(graded), 3
                )
                if graded
                else None,
            }
            for name in criteria
        ],
    }


def update(old: dict[str, Any], new: dict[str, Any]) -> dict[str, Any]:
    """``old`` results with the students of ``new`` (a regrade of some of them) in their place, the
    others kept; the summary and the similar groups made again over everyone."""
    if old.get("assignment", {}).get("name") != new["assignment"]["name"]:
        raise UserError(
            f"--update: those results are of assignment '{old.get('assignment', {}).get('name')}', "
            f"not '{new['assignment']['name']}' (hint: give the results of the same assignment)"
        )
    regraded = {s["name"]: s for s in new["students"]}
    students = [regraded.pop(s["name"], s) for s in old.get("students", [])] + list(regraded.values())
    wall = old.get("summary", {}).get("wall_time", 0.0) + new["summary"]["wall_time"]
    criteria = [c["name"] for c in new["assignment"]["criteria"]]
    return new | {
        "students": students,
        "summary": summary(students, criteria, wall) | {"confinement": new["summary"].get("confinement")},
        "similar": similar_groups(students),
    }


def _student(assignment: Assignment, worlds: list[World], entry: Entry, commands: Commands) -> dict[str, Any]:
    """One student's entry of results.json."""
    submission = entry.submission
    runs = sorted(entry.runs, key=lambda r: r["index"])
    task = entry.task
    if task is not None and len(runs) < task.runs and entry.status == "graded":
        entry.status = "error"
        entry.messages.append(f"only {len(runs)} of {task.runs} runs were made (the grade was stopped)")
    world_of = {w.name: w for w in worlds}
    for run in runs:
        run["reproduce"] = commands.run(str(submission.file), world_of[run["variant"]], run["seed"])
        run["check"] = commands.check(str(submission.file), run["variant"], run["seed"])
    criteria: list[dict[str, Any]] = (
        [_criterion(c, runs) for c in assignment.criteria]
        if entry.status == "graded"
        else [
            {
                "name": c.name,
                "points": c.points,
                "earned": 0.0,
                "passed": False,
                "runs": 0,
                "passed_runs": 0,
                "variants": [],
                "feedback": f"not graded: the submission is {entry.status} (see its messages)",
                "where": None,
            }
            for c in assignment.criteria
        ]
    )
    earned = sum(c["earned"] for c in criteria)
    score = round(max(0.0, earned - sum(f.points for f in entry.findings)), 3) if entry.status == "graded" else 0.0
    return {
        "name": submission.name,
        "file": str(submission.file) if submission.file else None,
        "status": entry.status,
        "score": score,
        "max": assignment.max_points,
        "penalty": round(score - earned, 3) if entry.status == "graded" else 0.0,
        "messages": entry.messages,
        "criteria": criteria,
        "palette": [f.to_json() for f in entry.findings],
        "coverage": _coverage(entry.plan, runs),
        "shape": tree_shape(entry.plan) if entry.plan is not None else None,
        "runs": [{k: v for k, v in r.items() if k not in ("kind", "node_stats")} for r in runs],
    }


@dataclass
class Commands:
    """The commands a results file gives to run a submission again: ``thymio-bt run`` to watch a
    run, ``thymio-bt check`` to judge it as the grader did; files named relative to the results'
    folder (a shipped maze or assignment by its name), never by the grader's absolute paths."""

    assignment: Assignment
    path: Path
    relative_to: Path | None = None

    def _ref(self, file: str | Path) -> str:
        return os.path.relpath(Path(file).resolve(), (self.relative_to or Path.cwd()).resolve())

    def run(self, file: str, world: World, seed: int) -> str:
        """The ``thymio-bt run`` command of one run."""
        args = ["thymio-bt", "run", self._ref(file), *world.run_arguments(self.relative_to), "--seed", str(seed)]
        if self.assignment.time_limit is not None:
            args += ["--set", f"time_limit={self.assignment.time_limit:g}"]
        return shlex.join(args)

    def check(self, file: str, variant: str, seed: int) -> str:
        """The ``thymio-bt check`` command that runs and judges one run as the grader did."""
        from thymio_bt.data import ASSIGNMENTS

        shipped = ASSIGNMENTS / self.path.name
        assignment = (
            self.path.stem if shipped.is_file() and shipped.resolve() == self.path.resolve() else self._ref(self.path)
        )
        return shlex.join(
            ["thymio-bt", "check", assignment, self._ref(file), "--variant", variant, "--seed", str(seed)]
        )


def _criterion(criterion: Criterion, runs: list[dict[str, Any]]) -> dict[str, Any]:
    """A criterion's line for one student. A variant passes when at least ``pass_rate`` of its
    runs passed; shared credit gives each passed variant its share of the points, ``credit: all``
    the points only when every variant passed."""
    judged = [(r, r["criteria"][criterion.name]) for r in runs if criterion.name in r["criteria"]]
    variants = _variants(criterion, judged)
    passed = bool(variants) and all(v["passed"] for v in variants)
    counts = criterion.credit == "shared" or passed
    for v in variants:
        v["earned"] = round(criterion.points / len(variants), 3) if v["passed"] and counts else 0.0
    earned = criterion.points if passed else round(sum(v["earned"] for v in variants), 3)
    feedback, where = _first_failure(judged)
    return {
        "name": criterion.name,
        "points": criterion.points,
        "earned": earned,
        "passed": passed,
        "runs": len(judged),
        "passed_runs": sum(j["passed"] for _, j in judged),
        "variants": variants,
        "feedback": feedback,
        "where": where,
    }


def _variants(criterion: Criterion, judged: list[tuple[dict[str, Any], dict[str, Any]]]) -> list[dict[str, Any]]:
    """A criterion's line for each variant of the (run, judgement) pairs, in the order they ran."""
    variants = []
    for name in dict.fromkeys(r["variant"] for r, _ in judged):
        mine = [j for r, j in judged if r["variant"] == name]
        passed_runs = sum(j["passed"] for j in mine)
        passed = passed_runs >= criterion.pass_rate * len(mine) - 1e-9
        feedback = next((j["feedback"] for j in mine if not j["passed"]), None)
        variants.append(
            {"name": name, "runs": len(mine), "passed_runs": passed_runs, "passed": passed, "feedback": feedback}
        )
    return variants


def _first_failure(judged: list[tuple[dict[str, Any], dict[str, Any]]]) -> tuple[str | None, Any]:
    """The feedback line and the place in the tree of a criterion's first failed run; None, None if none failed."""
    failed = [(r, j) for r, j in judged if not j["passed"]]
    if not failed:
        return None, None
    run, first = failed[0]
    return feedback_line(run, first["feedback"], len(failed), len(judged)), first["where"] or run.get("where")


def _coverage(plan: Any, runs: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The tree's coverage over the student's runs (None when nothing was read)."""
    if plan is None:
        return None
    from thymio_bt.run.coverage import Coverage

    coverage = Coverage.of(plan)
    for run in runs:
        if run.get("node_stats"):
            coverage.add(run["node_stats"])
    return coverage.to_json()
