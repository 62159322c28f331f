"""``thymio-bt replay`` and ``thymio-bt export``: what a run log gives without running the mission again.

``replay`` redraws a run (summary line, pictures, a window) from its ``--log`` file; ``export``
converts a log into another format (rosbag2 ``.mcap``, a Groot2 ``.btlog``, ...).

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["export", "run.jsonl"])
    >>> result.exit_code
    2
    >>> print(result.output, end="")
    error: nothing to write (hint: -o run.mcap, or --btlog run.btlog)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, cast

import click

from thymio_bt.cli.app import fail, main, path_option, pose_text, viewer_options
from thymio_bt.cli.pictures import Pictures
from thymio_bt.errors import UserError
from thymio_bt.outputs import STDOUT, Output, check_writable

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording
    from thymio_bt.logs.records import LogEnd, LogHeader, TickRecord


@main.command()
@click.argument("log", type=click.Path(path_type=Path))
@path_option("--plot", help="Draw the path in the maze (PNG).")
@path_option("--plot-signals", help="Draw the signals (PNG).")
@path_option("--gif", help="Animate the run.")
@viewer_options
@click.option("--partial", is_flag=True, help="Replay a damaged log up to its first damaged line.")
def replay(
    log: Path,
    plot: Path | None,
    plot_signals: Path | None,
    gif: Path | None,
    view: bool,
    speedup: float | None,
    partial: bool,
) -> None:
    """Redraw a run from its --log FILE.jsonl without re-running it."""
    from thymio_bt.logs import read_log

    pictures = Pictures(plot, plot_signals, gif)
    try:
        if view:
            from thymio_bt.viz.display import require_display

            require_display("without a display, draw the log to files: --plot run.png, --gif run.gif (or .mp4)")
        pictures.check()
        recording = read_log(log, partial)
        damage_note(log, recording)
        _replay_summary(recording)
        if not (pictures.wanted or view):
            click.echo(
                "nothing to draw (hint: --view, --plot FILE.png, --plot-signals FILE.png or --gif FILE.gif)", err=True
            )
        pictures.draw(recording, 4.0 if speedup is None else speedup, quiet=False)
        if view:
            from thymio_bt.viz.window import replay as replay_in_window

            replay_in_window(recording, 1.0 if speedup is None else speedup)
    except UserError as exc:
        fail(exc)


def _replay_summary(recording: Recording) -> None:
    """The logged run's summary, as ``run`` prints it: status, time, ticks, final pose, collisions,
    and where and why it did not succeed."""
    end = recording.end
    status = end.get("status") or "UNFINISHED"  # a damaged log read with --partial has no end
    ticks = len(recording.samples)
    click.echo(f"{recording.mission}: {status} after {end.get('sim_time', 0):.1f} s simulated, {ticks} ticks")
    click.echo(f"  final pose: {pose_text(end.get('final_pose'))}")
    if "collisions" in end:
        click.echo(f"  collisions: {end['collisions']}")
    if end.get("failed_path"):
        click.echo(f"  failed at: {end['failed_path']}")
    if end.get("reason"):
        click.echo(f"  reason: [{end.get('code')}] {end['reason']}")


@main.command()
@click.argument("log", type=click.Path(path_type=Path))
@path_option(
    "--output",
    "-o",
    help="The log to write; its suffix picks the format (.jsonl, .mcap, .btlog, or a folder: rosbag2).",
)
@path_option("--btlog", metavar="OUT.btlog", help="Write a Groot2 log (BT.CPP's FileLogger2 file).")
@click.option("--partial", is_flag=True, help="Export a damaged log up to its first damaged line.")
def export(log: Path, output: Path | None, btlog: Path | None, partial: bool) -> None:
    """Convert the run log LOG into another format (e.g. a JSON-lines log into a rosbag2 .mcap)."""
    try:
        from thymio_bt.logs import read_log

        targets = [p for p in (output, btlog) if p is not None]
        for target, option in ((output, "--output"), (btlog, "--btlog")):
            if target is not None and str(target) != STDOUT:
                check_writable(target, option)
        if not targets:
            raise UserError("nothing to write (hint: -o run.mcap, or --btlog run.btlog)")
        recording = read_log(log, partial)
        damage_note(log, recording)
        if not recording.header.get("tree"):
            raise UserError(
                f"{log} was written before logs carried their tree (hint: run the mission again "
                f"with --log to export it)"
            )
        for target in targets:
            _write_log(recording, target)
            click.echo(f"wrote {target}", err=True)
    except UserError as exc:
        fail(exc)


def _write_log(recording: Recording, target: Path) -> None:
    """Write ``recording`` to ``target`` in the format its suffix names: whole or not at all (the
    writer writes a staged file of the same suffix, renamed over the target once closed)."""
    if str(target) == STDOUT:
        _write_records(recording, target)
        return
    output = Output(target, "--output")
    with output.staged() if target.suffix else output.staged_folder() as staged:  # a rosbag2 folder
        _write_records(recording, staged)


def _write_records(recording: Recording, target: Path) -> None:
    """The records of ``recording`` through the writer of ``target``'s format (closed however it ends)."""
    from thymio_bt.logs import open_writer

    writer = open_writer(target)
    try:
        # the records as read_log parsed them: the log formats' shapes, which a Recording keeps as plain dicts
        writer.header(cast("LogHeader", recording.header))
        for sample in recording.samples:
            writer.tick(cast("TickRecord", sample))
        writer.end(cast("LogEnd", {**recording.end, "events": recording.events}))
    finally:
        writer.close()


def damage_note(log: Path, recording: Recording) -> None:
    """Say where a ``--partial`` read of ``log`` stopped (nothing when the log was whole)."""
    line = recording.header.get("damaged_at")
    if line:
        click.echo(f"{log}:{line}: damaged line; kept the {len(recording.samples)} ticks before it", err=True)
