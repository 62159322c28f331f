"""Grade a class: every submission in every world of the assignment, scored on its criteria.

The grader reads each submission without running its code (its plan, its palette), then runs it
in child processes of its own (:mod:`.isolation`), locally or on a Dask cluster, and scores each
criterion on the share of its runs that passed. It writes nothing itself: :func:`grade` returns
the results (the ``results.json`` contract of docs/grading.md).

Example::

    >>> results = grade("assignments/course_part1_2.yaml", ["examples/class/ada", "examples/class/chen"])
    >>> [(s["name"], s["status"], s["score"], s["max"]) for s in results["students"]]
    [('ada', 'graded', 10.0, 10.0), ('chen', 'graded', 1.0, 10.0)]
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
from thymio_bt.grade.assignment import Assignment, load_assignment, resolve_assignment
from thymio_bt.grade.isolation import ForkPool, Limits
from thymio_bt.grade.palette import Finding, check_palette
from thymio_bt.grade.student import StudentTask, died_message, grade_runs
from thymio_bt.grade.submissions import Submission, find_submissions
from thymio_bt.grade.worlds import World, make_worlds

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
    sandbox: str = "plugins",
) -> dict[str, Any]:
    """Grade ``submissions`` (files or folders) on the assignment; the results as JSON data.
    Generated mazes go to ``worlds`` (a new temporary folder when None). ``executor``: an object
    with ``imap_unordered`` (:class:`~thymio_bt.run.distributed.DaskExecutor`) to run the
    students on a cluster instead of ``workers`` local processes. ``started`` is told how many
    runs each student will make, once the submissions are read; ``progress`` hears each run end.
    ``sandbox``: whose trees tick in a confined process of their own (:mod:`.sandbox`): those of
    submissions with plugins (``plugins``), or every one (``always``: slower, for measurements)."""
    began = time.perf_counter()
    path = resolve_assignment(assignment_file)
    assignment = load_assignment(path)
    folder = worlds or Path(tempfile.mkdtemp(prefix="thymio-bt-worlds-"))
    made = make_worlds(assignment, path, folder)
    entries = [_read(s, assignment, made) for s in find_submissions(submissions, assignment.submission)]
    tasks = [e.task for e in entries if e.task is not None]
    for each in tasks:
        each.sandboxed = each.sandboxed or (sandbox == "always" and each.run_plugins)
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
        _warm()
        sandboxed = any(t.sandboxed for t in tasks)
        # a confined student is two processes that take turns (the simulation, its tree): twice as
        # many at once keep the cores busy while each waits for the other
        parallel = 2 * workers if sandboxed else workers
        with _zygote(sandboxed):
            ForkPool[StudentTask](parallel, _limits(assignment), progress=heard, stop=stop).run(
                tasks, grade_runs, lambda t: t.runs
            )
    else:
        for name, messages in executor.imap_unordered(graded_remotely, tasks):
            task = by_name[name].task
            assert task is not None
            for message in messages:
                heard(task, message)
            if stop():
                break
    if stop():  # a signal: the students whose runs were not all made say so
        for entry in entries:
            if entry.task is not None and len(entry.runs) < entry.task.runs and entry.status == "graded":
                entry.status = "interrupted"
                entry.messages.append(f"interrupted after {len(entry.runs)} of {entry.task.runs} runs")
    return results(assignment, path, made, entries, time.perf_counter() - began)


def _warm() -> None:
    """Before the children are forked, import and run once what every run needs (a shipped
    mission, no student's code): each child inherits it warm instead of paying for it again
    (0.1 s of a student's 0.5 s)."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    Run(load_mission("maze_part1_2"), node_stats=True).run()


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
    return Limits(cpu=limits.cpu, memory_mib=limits.memory, wall=limits.wall or 3 * limits.cpu + 5)


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
    from thymio_bt.mission.unrun_plugins import UncheckedParams

    stand_ins = any(getattr(cls, "Params", None) is UncheckedParams for _, cls in mission.registry.items())
    return stand_ins or any(p.suffix == ".py" for p in mission.sources)


def results(
    assignment: Assignment, path: Path, worlds: list[World], entries: list[Entry], wall: float
) -> dict[str, Any]:
    """The results.json data."""
    students = [_student(assignment, worlds, e) for e in entries]
    graded = [s for s in students if s["status"] == "graded"]
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
                }
                for w in worlds
            ],
        },
        "students": students,
        "summary": {
            "students": len(students),
            **{s: sum(t["status"] == s for t in students) for s in ("graded", "invalid", "error", "interrupted")},
            "runs": sum(len(s["runs"]) for s in students),
            "wall_time": round(wall, 3),
            "confinement": _confinement(assignment, entries),
            "mean_score": round(sum(s["score"] for s in students) / len(students), 3) if students else None,
            "criteria": [
                {
                    "name": c.name,
                    "pass_rate": round(
                        sum(sc["passed"] for s in graded for sc in s["criteria"] if sc["name"] == c.name) / len(graded),
                        3,
                    )
                    if graded
                    else None,
                }
                for c in assignment.criteria
            ],
        },
    }


def _student(assignment: Assignment, worlds: list[World], entry: Entry) -> dict[str, Any]:
    """One student's entry of results.json."""
    submission = entry.submission
    runs = sorted(entry.runs, key=lambda r: r["index"])
    task = entry.task
    if task is not None and len(runs) < task.runs and entry.status == "graded":
        entry.status = "error"
        entry.messages.append(f"only {len(runs)} of {task.runs} runs were made (the grade was stopped)")
    world_of = {w.name: w for w in worlds}
    for run in runs:
        world = world_of[run["variant"]]
        args = ["thymio-bt", "run", str(submission.file), *world.run_arguments(), "--seed", str(run["seed"])]
        if assignment.time_limit is not None:
            args += ["--set", f"time_limit={assignment.time_limit:g}"]
        run["reproduce"] = shlex.join(args)
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
                "feedback": f"not graded: the submission is {entry.status} (see its messages)",
                "where": None,
            }
            for c in assignment.criteria
        ]
    )
    earned = sum(c["earned"] for c in criteria) - sum(f.points for f in entry.findings)
    return {
        "name": submission.name,
        "file": str(submission.file) if submission.file else None,
        "status": entry.status,
        "score": round(max(0.0, earned), 3) if entry.status == "graded" else 0.0,
        "max": assignment.max_points,
        "messages": entry.messages,
        "criteria": criteria,
        "palette": [f.to_json() for f in entry.findings],
        "coverage": _coverage(entry.plan, runs),
        "runs": [{k: v for k, v in r.items() if k not in ("kind", "node_stats")} for r in runs],
    }


def _criterion(criterion: Any, runs: list[dict[str, Any]]) -> dict[str, Any]:
    """A criterion's line for one student: passed when enough of its runs passed it."""
    judged = [(r, r["criteria"][criterion.name]) for r in runs if criterion.name in r["criteria"]]
    passed_runs = sum(j["passed"] for _, j in judged)
    passed = bool(judged) and passed_runs >= criterion.pass_rate * len(judged) - 1e-9
    failed = [(r, j) for r, j in judged if not j["passed"]]
    feedback = None
    where = None
    if failed:
        run, first = failed[0]
        feedback = (
            f"{first['feedback']} (variant {run['variant']}, seed {run['seed']}, robot {run['robot']}; "
            f"failed {len(failed)} of {len(judged)} runs)"
        )
        where = first["where"] or run.get("where")
    return {
        "name": criterion.name,
        "points": criterion.points,
        "earned": criterion.points if passed else 0.0,
        "passed": passed,
        "runs": len(judged),
        "passed_runs": passed_runs,
        "feedback": feedback,
        "where": where,
    }


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
