"""Grade a class: every submission in every world of the assignment, scored on its criteria.

The grader reads each submission without running its code (its plan, its palette), then runs it
in child processes of its own (:mod:`.isolation`), locally or on a Dask cluster, and scores each
criterion on the share of its runs that passed. It writes nothing itself: :func:`grade` returns
the results (:class:`~.results.ClassResults`: the ``results.json`` contract of docs/grading.md),
scored by :mod:`.scoring`.

Example::

    >>> results = grade("assignments/course_part1_2.yaml", ["examples/class/ada", "examples/class/chen"])
    >>> [(s.name, s.status, s.score, s.max) for s in results.students]
    [('ada', <StudentStatus.GRADED: 'graded'>, 11.0, 11.0), ('chen', <StudentStatus.GRADED: 'graded'>, 2.0, 11.0)]
    >>> [p.message for p in results.students[1].palette], results.summary.runs
    (['WallFollow is not allowed in this assignment'], 24)
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from thymio_bt.errors import UserError
from thymio_bt.grade.assignment import Assignment, resolve_assignment
from thymio_bt.grade.isolation import ForkPool, Limits
from thymio_bt.grade.palette import check_palette
from thymio_bt.grade.results import ClassResults, RunMessage, StudentStatus
from thymio_bt.grade.scoring import Entry, class_results
from thymio_bt.grade.student import StudentTask, grade_runs, read_message
from thymio_bt.grade.submissions import Submission, find_submissions
from thymio_bt.grade.worlds import World, load_worlds

if TYPE_CHECKING:
    from thymio_bt.plan.model import Mission

#: called with (student, its run) as each run ends, in the grader's process
Progress = Callable[[str, RunMessage], None]


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
) -> ClassResults:
    """Grade ``submissions`` (files or folders) on the assignment: the class's results.
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
        run = read_message(task, message)
        by_name[task.name].runs.append(run)
        if progress is not None:
            progress(task.name, run)

    if executor is None:
        _run_here(tasks, workers, _limits(assignment), heard, stop)
    else:
        _run_on_cluster(executor, tasks, heard, stop)
    if stop():  # a signal: the students whose runs were not all made say so
        _interrupted(entries)
    wall = time.perf_counter() - began
    return class_results(assignment, path, made, entries, wall, relative_to, _confinement(assignment, entries))


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
        if entry.task is not None and len(entry.runs) < entry.task.runs and entry.status == StudentStatus.GRADED:
            entry.status = StudentStatus.INTERRUPTED
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
        entry.status, entry.messages = StudentStatus.INVALID, [submission.problem or "nothing handed in"]
        return entry
    try:
        mission = load_mission(submission.file, run_plugins=False)
    except UserError as exc:
        entry.status, entry.messages = StudentStatus.INVALID, [str(p) for p in exc.problems]
        return entry
    entry.plan = mission.tree
    entry.findings = check_palette(mission, assignment.palette)
    if any(f.rule == "plugins" for f in entry.findings):
        entry.status = StudentStatus.INVALID
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


def _has_plugins(mission: Mission) -> bool:
    """Whether a mission (read without running its plugins) names any plugin: its tree's code is then
    the student's, run in a confined process of its own."""
    from thymio_bt.plan.unrun_plugins import UncheckedParams

    stand_ins = any(cls.Params is UncheckedParams for _, cls in mission.registry.items())
    return stand_ins or any(p.suffix == ".py" for p in mission.sources)
