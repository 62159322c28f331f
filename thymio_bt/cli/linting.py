"""``thymio-bt lint``: the teaching lint of a mission (:mod:`thymio_bt.analysis.lint`), one finding per
line as ``file:line: [rule-id] message (hint: ...)`` on standard output; the count on standard error.

With ``--assignment``, the mission also runs once in each variant's world of the assignment, noise
off, its nodes counting their ticks; a condition never true in any variant and the nodes no variant
ran are findings too. Exit codes: 0 no finding, 1 findings, 2 a file that does not load.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["lint", "square"])
    >>> result.exit_code, result.output
    (0, 'square: no findings\\n')
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from thymio_bt.cli.app import fail, main, path_option
from thymio_bt.errors import UserError

if TYPE_CHECKING:
    from thymio_bt.analysis.lint import Finding
    from thymio_bt.plan.model import Mission


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@path_option(
    "--assignment",
    metavar="ASSIGNMENT.yaml",
    help="Also run MISSION once in each variant of this assignment (noise off; its plugins run) and report "
    "the conditions never true and the nodes never ticked.",
)
@click.option(
    "--plugins",
    is_flag=True,
    help="Import the mission's plugins, so that the rules know their nodes (runs their code).",
)
def lint(mission: Path, assignment: Path | None, plugins: bool) -> None:
    """Find what makes MISSION's tree not do what it seems to (unreachable nodes, reactive restarts,
    endless loops, a way ahead checked once before a longer drive, unused subtrees and parameters,
    values at the edge of their range)."""
    from thymio_bt.analysis.lint import lint_mission

    try:
        findings = lint_mission(mission, run_plugins=plugins)
        if assignment is not None:
            findings += assignment_findings(mission, assignment)
    except UserError as exc:
        fail(exc)
    for finding in findings:
        click.echo(str(finding))
    count = len(findings)
    click.echo(f"{mission.stem}: {count or 'no'} finding{'s' * (count != 1)}", err=True)
    sys.exit(1 if findings else 0)


def assignment_findings(mission: Path, assignment: Path) -> list[Finding]:
    """``never-true`` and ``never-ticked``: the coverage of one noise-free run of ``mission`` in each
    variant of ``assignment``."""
    from thymio_bt.analysis.lint import coverage_findings

    spec, coverage = assignment_coverage(mission, assignment)
    return coverage_findings(spec, coverage)


def assignment_coverage(mission: Path, assignment: Path) -> tuple[Mission, dict[str, Any]]:
    """The coverage JSON of one noise-free run of ``mission`` in each variant of ``assignment``
    (its first seed, the assignment's time limit), and the mission as the last variant loaded it."""
    from thymio_bt.grade.assignment import load_assignment, resolve_assignment
    from thymio_bt.grade.worlds import variant_mission
    from thymio_bt.run.coverage import Coverage
    from thymio_bt.run.runner import Run

    assignment = resolve_assignment(assignment)  # a shipped one by name: its mazes are beside it
    task = load_assignment(assignment)
    merged: Coverage | None = None
    spec: Mission | None = None
    for variant in task.variants:
        quiet = variant.model_copy(update={"noise": "off"})
        try:
            spec = variant_mission(mission, quiet, run_plugins=True, base=assignment.parent)
        except ValueError as exc:  # a world the variant cannot make (a maze the generator cannot draw)
            raise UserError(f"{assignment}: variant '{variant.name}': {exc}") from None
        if task.time_limit is not None:
            spec = replace(spec, time_limit=task.time_limit)
        result = Run(spec, variant.seed_list[0], node_stats=True).run()
        merged = merged or Coverage.of(spec.tree)
        merged.add(result.node_stats)
    assert spec is not None and merged is not None  # an assignment has at least one variant
    return spec, merged.to_json()
