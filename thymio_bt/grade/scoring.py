"""A class's runs scored: each student's criteria (a variant passes at ``pass_rate`` of its runs,
the points shared or all-or-nothing), the palette's penalty, the tree's coverage, the commands
that make each run again, and the class's summary; an earlier grade updated with a regrade.

Example (the score of a criterion from its runs' judgements)::

    >>> from thymio_bt.grade.assignment import Criterion
    >>> from thymio_bt.run.result import RunStatus
    >>> def run(variant, passed):
    ...     feedback = None if passed else "stopped 7.0 cm from the wall"
    ...     return RunRecord(index=0, variant=variant, seed=0, robot="course", status=RunStatus.SUCCESS,
    ...                      criteria={"stops": Judged(passed=passed, feedback=feedback)})
    >>> runs = [run("course", True), run("course", True), run("box", False)]
    >>> scored = criterion_score(Criterion(name="stops", points=2, finishes=True), runs)
    >>> scored.earned, [(v.name, v.passed, v.earned) for v in scored.variants]
    (1.0, [('course', True, 1.0), ('box', False, 0.0)])
    >>> scored.feedback
    'stopped 7.0 cm from the wall (variant box, seed 0, robot course; failed 1 of 3 runs)'
"""

from __future__ import annotations

import os
import shlex
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from thymio_bt.errors import UserError
from thymio_bt.grade.assignment import Assignment, Criterion
from thymio_bt.grade.palette import Finding
from thymio_bt.grade.redact import feedback_line
from thymio_bt.grade.results import (
    AssignmentInfo,
    ClassResults,
    CriterionInfo,
    CriterionRate,
    CriterionScore,
    Judged,
    RunMessage,
    RunRecord,
    StudentResult,
    StudentStatus,
    Summary,
    VariantInfo,
    VariantScore,
)
from thymio_bt.grade.similarity import similar_groups, tree_shape
from thymio_bt.grade.student import StudentTask
from thymio_bt.grade.submissions import Submission
from thymio_bt.grade.worlds import World
from thymio_bt.plan.model import NodePlan


@dataclass
class Entry:
    """One student as the grader goes: their submission, the plan read from it, their runs."""

    submission: Submission
    status: StudentStatus = StudentStatus.GRADED
    messages: list[str] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    plan: NodePlan | None = None
    task: StudentTask | None = None
    runs: list[RunMessage] = field(default_factory=list)


def class_results(
    assignment: Assignment,
    path: Path,
    worlds: list[World],
    entries: list[Entry],
    wall: float,
    relative_to: Path | None = None,
    confinement: str | None = None,
) -> ClassResults:
    """The class's results: the assignment as graded, each student's, the summary (with what
    ``confinement`` held around the students' code), the similar trees."""
    commands = Commands(assignment, path, relative_to)
    students = [_student(assignment, worlds, e, commands) for e in entries]
    info = AssignmentInfo(
        name=assignment.name,
        title=assignment.title,
        file=str(path),
        max=assignment.max_points,
        criteria=[
            CriterionInfo(
                name=c.name,
                points=c.points,
                variants=c.variants or [w.name for w in worlds],
                pass_rate=c.pass_rate,
                credit=c.credit,
                check=c.check,
            )
            for c in assignment.criteria
        ],
        palette=assignment.palette,
        variants=[
            VariantInfo(
                name=w.name,
                maze=str(w.maze_file) if w.maze_file else None,
                start=w.start,
                robot=w.robot,
                seeds=w.seeds,
                noise=w.settings.get("noise.wheel", "0") != "0",
                visibility="hidden" if w.visibility == "hidden" else "public",
            )
            for w in worlds
        ],
    )
    criteria = [c.name for c in assignment.criteria]
    return ClassResults(
        assignment=info,
        students=students,
        summary=summary(students, criteria, wall, confinement),
        similar=similar_groups([(s.name, s.shape) for s in students]),
    )


def summary(students: list[StudentResult], criteria: list[str], wall: float, confinement: str | None) -> Summary:
    """The ``summary`` of ``students``: counts, runs, the mean score, each criterion's pass rate
    over the graded students."""
    graded = [s for s in students if s.status == StudentStatus.GRADED]

    def count(status: StudentStatus) -> int:
        return sum(s.status == status for s in students)

    return Summary(
        students=len(students),
        graded=count(StudentStatus.GRADED),
        invalid=count(StudentStatus.INVALID),
        error=count(StudentStatus.ERROR),
        interrupted=count(StudentStatus.INTERRUPTED),
        runs=sum(len(s.runs) for s in students),
        wall_time=round(wall, 3),
        mean_score=round(sum(s.score for s in students) / len(students), 3) if students else None,
        criteria=[
            CriterionRate(
                name=name,
                pass_rate=round(sum(c.passed for s in graded for c in s.criteria if c.name == name) / len(graded), 3)
                if graded
                else None,
            )
            for name in criteria
        ],
        confinement=confinement,
    )


def update(old: ClassResults, new: ClassResults) -> ClassResults:
    """``old`` results with the students of ``new`` (a regrade of some of them) in their place, the
    others kept; the summary and the similar groups made again over everyone."""
    if old.assignment.name != new.assignment.name:
        raise UserError(
            f"--update: those results are of assignment '{old.assignment.name}', "
            f"not '{new.assignment.name}' (hint: give the results of the same assignment)"
        )
    regraded = {s.name: s for s in new.students}
    students = [regraded.pop(s.name, s) for s in old.students] + list(regraded.values())
    wall = old.summary.wall_time + new.summary.wall_time
    criteria = [c.name for c in new.assignment.criteria]
    return new.model_copy(
        update={
            "students": students,
            "summary": summary(students, criteria, wall, new.summary.confinement),
            "similar": similar_groups([(s.name, s.shape) for s in students]),
        }
    )


def _student(assignment: Assignment, worlds: list[World], entry: Entry, commands: Commands) -> StudentResult:
    """One student's results."""
    submission = entry.submission
    messages = sorted(entry.runs, key=lambda r: r.index)
    task = entry.task
    if task is not None and len(messages) < task.runs and entry.status == StudentStatus.GRADED:
        entry.status = StudentStatus.ERROR
        entry.messages.append(f"only {len(messages)} of {task.runs} runs were made (the grade was stopped)")
    world_of = {w.name: w for w in worlds}
    runs = [
        m.record().model_copy(
            update={
                "reproduce": commands.run(str(submission.file), world_of[m.variant], m.seed),
                "check": commands.check(str(submission.file), m.variant, m.seed),
            }
        )
        for m in messages
    ]
    graded = entry.status == StudentStatus.GRADED
    criteria = (
        [criterion_score(c, runs) for c in assignment.criteria]
        if graded
        else [
            CriterionScore(
                name=c.name,
                points=c.points,
                feedback=f"not graded: the submission is {entry.status} (see its messages)",
            )
            for c in assignment.criteria
        ]
    )
    earned = sum(c.earned for c in criteria)
    score = round(max(0.0, earned - sum(f.points for f in entry.findings)), 3) if graded else 0.0
    return StudentResult(
        name=submission.name,
        file=str(submission.file) if submission.file else None,
        status=entry.status,
        score=score,
        max=assignment.max_points,
        penalty=round(score - earned, 3) if graded else 0.0,
        messages=entry.messages,
        criteria=criteria,
        palette=entry.findings,
        coverage=_coverage(entry.plan, messages),
        shape=tree_shape(entry.plan) if entry.plan is not None else None,
        runs=runs,
    )


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


def criterion_score(criterion: Criterion, runs: list[RunRecord]) -> CriterionScore:
    """A criterion's line for one student. A variant passes when at least ``pass_rate`` of its
    runs passed; shared credit gives each passed variant its share of the points, ``credit: all``
    the points only when every variant passed."""
    judged = [(r, r.criteria[criterion.name]) for r in runs if criterion.name in r.criteria]
    variants = _variants(criterion, judged)
    passed = bool(variants) and all(v.passed for v in variants)
    counts = criterion.credit == "shared" or passed
    for v in variants:
        v.earned = round(criterion.points / len(variants), 3) if v.passed and counts else 0.0
    earned = criterion.points if passed else round(sum(v.earned for v in variants), 3)
    feedback, where = _first_failure(judged)
    return CriterionScore(
        name=criterion.name,
        points=criterion.points,
        earned=earned,
        passed=passed,
        runs=len(judged),
        passed_runs=sum(j.passed for _, j in judged),
        variants=variants,
        feedback=feedback,
        where=where,
    )


def _variants(criterion: Criterion, judged: list[tuple[RunRecord, Judged]]) -> list[VariantScore]:
    """A criterion's line for each variant of the (run, judgement) pairs, in the order they ran."""
    variants = []
    for name in dict.fromkeys(r.variant for r, _ in judged):
        mine = [j for r, j in judged if r.variant == name]
        passed_runs = sum(j.passed for j in mine)
        passed = passed_runs >= criterion.pass_rate * len(mine) - 1e-9
        feedback = next((j.feedback for j in mine if not j.passed), None)
        variants.append(
            VariantScore(name=name, runs=len(mine), passed_runs=passed_runs, passed=passed, feedback=feedback)
        )
    return variants


def _first_failure(judged: list[tuple[RunRecord, Judged]]) -> tuple[str | None, str | None]:
    """The feedback line and the place in the tree of a criterion's first failed run; None, None if none failed."""
    failed = [(r, j) for r, j in judged if not j.passed]
    if not failed:
        return None, None
    run, first = failed[0]
    line = feedback_line(run.variant, run.seed, run.robot, first.feedback, len(failed), len(judged))
    return line, first.where or run.where


def _coverage(plan: NodePlan | None, runs: list[RunMessage]) -> dict[str, Any] | None:
    """The tree's coverage over the student's runs, as JSON (None when nothing was read)."""
    if plan is None:
        return None
    from thymio_bt.run.coverage import Coverage

    coverage = Coverage.of(plan)
    for run in runs:
        if run.node_stats:
            coverage.add(run.node_stats)
    return coverage.to_json()
