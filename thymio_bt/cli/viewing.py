"""``thymio-bt view``: a run log (or two) as one self-contained HTML page to scrub through.

``view LOG`` writes ``LOG.html`` beside the log (``-o`` elsewhere); ``view A B`` puts two runs side
by side, aligned by simulated time, with their first divergence (:mod:`thymio_bt.run.divergence`)
marked. Any log format the project reads works (JSON lines, MCAP, a .btlog with ``--poses`` for its
robot); docs/viewer.md tells the page.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["view", "missing.jsonl"])
    >>> result.exit_code, result.output.splitlines()[0]
    (2, 'error: missing.jsonl: log not found: missing.jsonl (hint: write one with run --log FILE.jsonl)')
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from thymio_bt.cli.app import fail, main, path_option
from thymio_bt.errors import UserError
from thymio_bt.outputs import check_writable

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording
    from thymio_bt.run.divergence import Divergence


def page_path(logs: tuple[Path, ...]) -> Path:
    """Where ``view`` writes without ``-o``: beside the first log, named for the log(s).

    >>> page_path((Path("runs/a.jsonl"),)), page_path((Path("a.jsonl"), Path("b.mcap")))
    (PosixPath('runs/a.html'), PosixPath('a_vs_b.html'))
    """
    name = "_vs_".join(log.stem for log in logs) + ".html"
    return logs[0].with_name(name)


def divergence_json(a: Recording, b: Recording) -> dict[str, Any] | None:
    """The two runs' first divergence as the page wants it (time, tick, reason), or None."""
    from thymio_bt.run.divergence import first_divergence

    return page_divergence(first_divergence(a, b))


def page_divergence(found: Divergence | None) -> dict[str, Any] | None:
    """A divergence (``view``'s, ``compare``'s with its tolerances) as the page marks it, or None."""
    return None if found is None else found.mark()


@main.command()
@click.argument("logs", nargs=-1, required=True, type=click.Path(path_type=Path), metavar="LOG [LOG2]")
@path_option("-o", "--out", help="The page to write (default: beside the first log, LOG.html).")
@click.option("--partial", is_flag=True, help="Show a damaged log up to its first damaged line.")
@click.option(
    "--poses",
    type=click.Path(path_type=Path),
    help="A log of the same run with poses (.jsonl, .mcap), for a .btlog LOG: its robot, the .btlog's tree.",
)
def view(logs: tuple[Path, ...], out: Path | None, partial: bool, poses: Path | None) -> None:
    """Write a run log (or two, side by side) as one HTML page: maze, robot, tree, blackboard and
    signals at any tick, with its first divergence for two runs."""
    from thymio_bt.logs import format_for, read_log
    from thymio_bt.viz.page import write_page

    try:
        if len(logs) > 2:
            raise UserError(f"view takes one or two logs, got {len(logs)} (hint: view A.jsonl B.jsonl)")
        target = out or page_path(logs)
        check_writable(target, "-o")
        recordings = [read_log(log, partial) for log in logs]
        if poses is not None:
            from thymio_bt.btcpp.btlog import with_poses

            if len(logs) != 1 or format_for(logs[0], reading=True).name != "btlog":
                raise UserError("--poses goes with one .btlog log (hint: view run.btlog --poses run.jsonl)")
            recordings = [with_poses(recordings[0], read_log(poses, partial))]
        divergence = divergence_json(*recordings) if len(recordings) == 2 else None
        labels = [log.stem for log in logs] if len(logs) == 2 else None
        written = write_page(recordings, target, divergence, labels)
    except UserError as exc:
        fail(exc)
    click.echo(f"wrote {written}" + (f" (first divergence at t = {divergence['time']} s)" if divergence else ""))
