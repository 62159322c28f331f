"""``thymio-bt grade``: a class's submissions run in the assignment's worlds and scored.

Exit codes: 0 every submission was graded (and, with ``--fail-under``, scored at least that); 1 one
scored less, or could not be graded (stopped, or the grader's error); 2 a bad assignment or command
line. A student's broken file is not an error of the grader: it is graded ``invalid``.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["grade", "assignments/course_part1_2.yaml", "nowhere/"])
    >>> result.exit_code, result.output
    (2, 'error: submission not found: nowhere (hint: give mission files or folders (subs/*))\\n')
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from thymio_bt.cli.app import fail, json_text, main, path_option, workers_or_dask
from thymio_bt.errors import UserError
from thymio_bt.outputs import Output
from thymio_bt.run.interrupts import Interrupts

if TYPE_CHECKING:
    from thymio_bt.grade.results import ClassResults, RunMessage


@main.command()
@click.argument("assignment", type=click.Path(path_type=Path))
@click.argument("submissions", nargs=-1, required=True, type=click.Path(path_type=Path))
@path_option("--out", help="Write the results JSON here (the contract of docs/grading.md).")
@path_option("--csv", "csv_file", help="Write a gradebook CSV here: a row per student, a column per criterion.")
@path_option("--junit", help="Write JUnit XML here: a testsuite per student, a testcase per criterion.")
@path_option(
    "--gradescope",
    help="Write Gradescope's autograder results.json here (one submission; hidden variants' tests after the due date).",
)
@path_option("--html", help="Write a static site into this folder: the class page and a page per student.")
@path_option(
    "--update",
    help="Regrade SUBMISSIONS into these results, keeping the others; written to --out (else this file).",
)
@click.option(
    "--for-students",
    is_flag=True,
    help="Write the --html pages for the students: nothing of a hidden variant's maze, path, start or commands.",
)
@path_option("--secret", help="The course's secret, for generated worlds with a secret seed (else THYMIO_BT_SECRET).")
@click.option("--workers", type=click.IntRange(1, 256), default=None, help="Processes (default: all cores).")
@click.option("--dask", default=None, metavar="ADDRESS", help="Grade on a Dask cluster (needs thymio-bt[dask]).")
@click.option(
    "--fail-under",
    type=click.FloatRange(0, 100_000),
    default=None,
    metavar="SCORE",
    help="Exit 1 when a student scored less than this.",
)
@click.option(
    "--require-confinement",
    is_flag=True,
    help="Exit 2 unless the OS confines plugins in files, network, signals and processes (Landlock ABI 6+).",
)
def grade(
    assignment: Path,
    submissions: tuple[Path, ...],
    out: Path | None,
    csv_file: Path | None,
    junit: Path | None,
    gradescope: Path | None,
    html: Path | None,
    update: Path | None,
    for_students: bool,
    secret: Path | None,
    workers: int | None,
    dask: str | None,
    fail_under: float | None,
    require_confinement: bool,
) -> None:
    """Grade SUBMISSIONS (mission files, or a folder per student) on ASSIGNMENT (a YAML file)."""
    try:
        outputs = _outputs(out, csv_file, junit, gradescope)
        previous = _previous(update) if update is not None else None
        if update is not None and out is None:
            outputs["out"] = Output(update, "--update")
        site = _checked_options(submissions, gradescope, html, for_students, workers, dask, require_confinement)
        results, interrupts = _graded(assignment, submissions, out or update, html, for_students, secret, workers, dask)
        if previous is not None:
            from thymio_bt.grade.scoring import update as updated

            results = updated(previous, results)
        from thymio_bt.grade.site_replay import take_replays

        replays = take_replays(results)  # the site's, not results.json's
        _write_reports(outputs, results)
        if site is not None:
            _write_site(results, site, replays, for_students)
    except UserError as exc:
        fail(exc)
    _exit(results, outputs, interrupts, fail_under)


def _outputs(out: Path | None, csv_file: Path | None, junit: Path | None, gradescope: Path | None) -> dict[str, Output]:
    """The report files asked for, by report name, each checked writable (in the options' order)."""
    named = (
        ("out", out, "--out"),
        ("csv", csv_file, "--csv"),
        ("junit", junit, "--junit"),
        ("gradescope", gradescope, "--gradescope"),
    )
    return {name: Output(path, option) for name, path, option in named if path is not None}


def _checked_options(
    submissions: tuple[Path, ...],
    gradescope: Path | None,
    html: Path | None,
    for_students: bool,
    workers: int | None,
    dask: str | None,
    require_confinement: bool,
) -> Path | None:
    """The options that must agree with each other, checked before anything runs; the ``--html``
    folder (made), if asked for."""
    if gradescope is not None and len(submissions) != 1:
        count = len(submissions)
        raise UserError(f"--gradescope grades one submission, got {count} (hint: Gradescope runs one at a time)")
    site = _site_folder(html) if html is not None else None
    workers_or_dask(workers, dask)
    if for_students and html is None:
        raise UserError("--for-students is about the --html pages (hint: add --html DIR)")
    if require_confinement:
        _check_confinement()
    return site


def _graded(
    assignment: Path,
    submissions: tuple[Path, ...],
    results_file: Path | None,
    html: Path | None,
    for_students: bool,
    secret: Path | None,
    workers: int | None,
    dask: str | None,
) -> tuple[ClassResults, Interrupts]:
    """The class graded (on a local pool or a Dask cluster, with progress on stderr), and the
    interrupts that may have stopped it."""
    import os

    from thymio_bt.cli.sweeps import dask_executor
    from thymio_bt.grade.grader import grade as run_grade
    from thymio_bt.grade.worlds import course_secret

    worlds = _worlds_folder(results_file, html)
    relative_to = worlds.parent if worlds is not None else None  # the commands name files from there
    # pages for students hold the public worlds' mazes (their commands name them), never a hidden one's
    hidden = (_worlds_folder(results_file, None) or _temporary()) if for_students else None
    with dask_executor(dask) as executor, Interrupts() as interrupts, _Progress() as progress:
        results = run_grade(
            assignment,
            submissions,
            workers=workers or os.cpu_count() or 1,
            worlds=worlds,
            executor=executor,
            progress=progress,
            stop=lambda: interrupts.signal is not None,
            started=progress.start,
            secret=course_secret(secret),
            relative_to=relative_to,
            hidden_worlds=hidden,
            replays=None if html is None else "public" if for_students else "all",
        )
    return results, interrupts


def _write_reports(outputs: dict[str, Output], results: ClassResults) -> None:
    """Each report asked for, written in this order: results JSON, gradebook CSV, JUnit, Gradescope."""
    from thymio_bt.grade.reports import gradebook_csv, junit_xml

    writers = {"out": _results_text, "csv": gradebook_csv, "junit": junit_xml, "gradescope": _gradescope_text}
    for name, text in writers.items():
        if name in outputs:
            outputs[name].write_text(text(results))


def _results_text(results: ClassResults) -> str:
    """results.json."""
    return json_text(results.to_json())


def _gradescope_text(results: ClassResults) -> str:
    """Gradescope's results.json of the one student graded."""
    from thymio_bt.grade.reports import gradescope_json

    if len(results.students) != 1:
        count = len(results.students)
        raise UserError(f"--gradescope: grades one submission, got {count} (hint: Gradescope runs one at a time)")
    return json_text(gradescope_json(results))


def _write_site(
    results: ClassResults, site: Path, replays: dict[tuple[str, int], dict[str, Any]], for_students: bool
) -> None:
    """The ``--html`` site, from results.json's content: the class page and a page per student
    (redacted for the students)."""
    from thymio_bt.grade.redact import for_students as redacted
    from thymio_bt.grade.site import write_site

    data = results.to_json()
    pages = write_site(redacted(data) if for_students else data, site, replays, for_students)
    click.echo(f"wrote the site: {pages[0]} ({len(pages)} pages)", err=True)


def _exit(results: ClassResults, outputs: dict[str, Output], interrupts: Interrupts, fail_under: float | None) -> None:
    """The summary table, then the exit: the interrupt's code, 1 for a score under ``--fail-under``
    or a submission the grader could not grade, else 0."""
    from thymio_bt.grade.reports import summary_table
    from thymio_bt.grade.results import StudentStatus

    to_stderr = any(o.is_stdout for o in outputs.values())
    click.echo(summary_table(results), err=to_stderr)
    click.echo(results.summary.confinement, err=to_stderr)
    if interrupts.signal:
        sys.exit(interrupts.exit_code)
    students = results.students
    below = fail_under is not None and any(s.score < fail_under - 1e-9 for s in students)
    sys.exit(1 if below or any(s.status == StudentStatus.ERROR for s in students) else 0)


def _previous(path: Path) -> ClassResults:
    """The results ``--update`` regrades into."""
    import json

    from thymio_bt.grade.results import ClassResults

    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise UserError(f"--update {path}: cannot read results from it: {exc}") from None
    try:
        return ClassResults.from_json(data)
    except ValueError as exc:
        raise UserError(f"--update {path}: {exc} (hint: give the --out file of thymio-bt grade)") from None


def _check_confinement() -> None:
    """``--require-confinement``: a user error when an area of the confinement is missing here."""
    from thymio_bt.errors import Problem
    from thymio_bt.grade.confine import plan

    held = plan()
    if held.missing:
        raise UserError(
            Problem(
                f"--require-confinement: {held.summary()}",
                hint="grade on Linux 6.12 or later with Landlock enabled, or leave out --require-confinement",
            )
        )


def _site_folder(path: Path) -> Path:
    """The ``--html`` folder: made if missing, refused if it is a file."""
    if path.exists() and not path.is_dir():
        raise UserError(f"--html {path}: is not a folder (hint: give a folder name, e.g. --html site/)")
    if not path.parent.is_dir():
        raise UserError(f"--html {path}: the folder {path.parent} does not exist (hint: mkdir -p {path.parent})")
    path.mkdir(exist_ok=True)
    return path


def _temporary() -> Path:
    """A new temporary folder (the hidden worlds' mazes, when the results are not written)."""
    import tempfile

    return Path(tempfile.mkdtemp(prefix="thymio-bt-hidden-worlds-"))


def _worlds_folder(out: Path | None, html: Path | None) -> Path | None:
    """Where generated mazes go: beside the results (so the reproduce commands name files that stay)."""
    if html is not None:
        return html / "worlds"
    if out is not None and str(out) != "-":
        return out.parent / f"{out.stem}_worlds"
    return None


class _Progress:
    """Students done / total, runs per second and the time left, on one line of a terminal; elsewhere
    (a log) a line per student graded."""

    def __init__(self) -> None:
        self.enabled = sys.stderr.isatty()
        self.students = 0
        self.runs = 0
        self.total_runs = 0
        self.done: dict[str, int] = {}
        self.failed: dict[str, int] = {}
        self.wanted: dict[str, int] = {}
        self.began = time.perf_counter()
        self.shown = 0.0

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.enabled and self.shown:
            click.echo("", err=True)

    def start(self, runs_per_student: dict[str, int]) -> None:
        """The grader is about to run: how many runs each student will make."""
        self.wanted = dict(runs_per_student)
        self.total_runs = sum(runs_per_student.values())
        self.began = time.perf_counter()

    def __call__(self, student: str, run: RunMessage) -> None:
        self.runs += 1
        self.done[student] = self.done.get(student, 0) + 1
        self.failed[student] = self.failed.get(student, 0) + run.broken
        if self.done[student] == self.wanted.get(student):
            self.students += 1
            if not self.enabled:  # a log (CI, a pipe): a line per student graded
                broken = self.failed[student]
                click.echo(
                    f"graded {self.students}/{len(self.wanted)}: {student}, {self.done[student]} runs"
                    + (f" ({broken} stopped or crashed)" if broken else ""),
                    err=True,
                )
        now = time.perf_counter()
        if not self.enabled or now - self.shown < 0.2 and self.runs < self.total_runs:
            return
        self.shown = now
        rate = self.runs / max(now - self.began, 1e-9)
        left = (self.total_runs - self.runs) / rate if rate else 0.0
        click.echo(
            f"\rgraded {self.students}/{len(self.wanted)} students, {self.runs}/{self.total_runs} runs, "
            f"{rate:.1f} runs/s, {left:.0f} s left ",
            err=True,
            nl=False,
        )
