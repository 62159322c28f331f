"""``thymio-bt check``: a student's mission judged as the grader judges it, before handing it in.

It runs the assignment's public variants (the same worlds, seeds, criteria and words as ``grade``)
and prints each criterion; ``--variant V --seed N`` runs and judges one run, the one a results
file's ``check`` command names. Exit codes: 0 every criterion passed and no palette rule is
broken; 1 one is not; 2 a bad assignment, mission or command line.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["check", "course_part1_2", "examples/class/ada/part1_2.yaml",
    ...                                    "--variant", "course", "--seed", "0"])
    >>> result.exit_code, result.output.splitlines()[0]
    (0, 'course_part1_2: variant course, seed 0 (1 run)')
    >>> CliRunner().invoke(main, ["check", "course_part1_2", "x.yaml", "--variant", "corse"]).output
    "error: no variant 'corse' in course_part1_2 (hint: did you mean 'course'?)\\n"
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import click

from thymio_bt.cli.app import fail, main, path_option
from thymio_bt.errors import Problem, UserError, did_you_mean

if TYPE_CHECKING:
    from thymio_bt.grade.results import ClassResults, StudentResult


@main.command()
@click.argument("assignment")
@click.argument("mission", type=click.Path(path_type=Path))
@click.option("--variant", default=None, help="Only this variant (hidden ones too, with the course's secret).")
@click.option("--seed", type=click.IntRange(0, 2**31), default=None, help="Only this noise seed.")
@path_option("--secret", help="The course's secret, for generated worlds with a secret seed (else THYMIO_BT_SECRET).")
@click.option("--workers", type=click.IntRange(1, 256), default=None, help="Processes (default: all cores).")
def check(
    assignment: str, mission: Path, variant: str | None, seed: int | None, secret: Path | None, workers: int | None
) -> None:
    """Judge MISSION on ASSIGNMENT's public variants as `thymio-bt grade` does."""
    import os

    from thymio_bt.grade.grader import grade
    from thymio_bt.grade.results import StudentStatus
    from thymio_bt.grade.worlds import World, course_secret

    def select(worlds: list[World]) -> list[World]:
        if variant is None:
            chosen = [w for w in worlds if w.visibility == "public"]
        else:
            chosen = [w for w in worlds if w.name == variant]
            if not chosen:
                hint = did_you_mean(variant, [w.name for w in worlds])
                raise UserError(Problem(f"no variant '{variant}' in {assignment}", hint=hint))
        return [replace(w, seeds=[seed]) for w in chosen] if seed is not None else chosen

    try:
        results = grade(
            assignment, [mission], workers=workers or os.cpu_count() or 1, secret=course_secret(secret), select=select
        )
    except UserError as exc:
        fail(exc)
    (student,) = results.students
    click.echo(_heading(results, variant, seed))
    click.echo(report(student))
    passed = student.status == StudentStatus.GRADED and all(c.passed for c in student.criteria) and not student.palette
    sys.exit(0 if passed else 1)


def _heading(results: ClassResults, variant: str | None, seed: int | None) -> str:
    from thymio_bt.grade.checks import count

    variants = results.assignment.variants
    runs = results.summary.runs
    name = results.assignment.name
    if variant is not None:
        seeds = f", seed {seed}" if seed is not None else ""
        return f"{name}: variant {variant}{seeds} ({count(runs, 'run')})"
    listed = ", ".join(v.name for v in variants)
    return f"{name}: {count(len(variants), 'public variant')} ({listed}), {count(runs, 'run')}"


def report(student: StudentResult) -> str:
    """What ``check`` prints of a student's results: each criterion passed or not, with the
    grader's words and the place to look, the palette's findings, the score.

    >>> from thymio_bt.grade.results import CriterionScore, StudentResult
    >>> print(report(StudentResult(name="ada", status="graded", score=1.0, max=3.0, criteria=[
    ...     CriterionScore(name="stops", earned=1.0, points=2.0, where="m.yaml:10",
    ...                    feedback="stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm"),
    ...     CriterionScore(name="ends", passed=True, earned=1.0, points=1.0)])))
    FAIL  stops  1 / 2
          stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm
          at m.yaml:10
    pass  ends  1 / 1
    score here: 1 / 3
    """
    from thymio_bt.grade.results import StudentStatus

    if student.status != StudentStatus.GRADED:
        return "\n".join([f"not graded: the submission is {student.status.value}", *student.messages])
    lines = []
    for c in student.criteria:
        lines.append(f"{'pass' if c.passed else 'FAIL'}  {c.name}  {c.earned:g} / {c.points:g}")
        if not c.passed:
            lines.append(f"      {c.feedback}")
            if c.where:
                lines.append(f"      at {c.where}")
    for finding in student.palette:
        where = f"{finding.where}: " if finding.where else ""
        lines.append(f"FAIL  palette: {where}{finding.message} (-{finding.points:g})")
    lines.append(f"score here: {student.score:g} / {student.max:g}")
    return "\n".join(lines)
