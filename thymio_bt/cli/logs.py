"""``thymio-bt replay`` and ``thymio-bt export``: what a run log gives without running the mission again.

``replay`` redraws a run (summary line, pictures, a window) from its ``--log`` file; with
``--mission CHANGED.yaml`` (or ``--set``) it asks what if: the changed tree re-ticked against the
recorded readings (:mod:`thymio_bt.run.whatif`). ``export`` converts a log into another format
(rosbag2 ``.mcap``, a Groot2 ``.btlog``, ...).

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

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import click

from thymio_bt.cli.app import fail, json_text, main, parse_overrides, path_option, pose_text, viewer_options
from thymio_bt.cli.pictures import Pictures
from thymio_bt.errors import UserError
from thymio_bt.outputs import STDOUT, Output, check_writable

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording
    from thymio_bt.run.whatif import WhatIf


@dataclass(frozen=True)
class Drawn:
    """What a replay draws besides its summary: the ``pictures``, the ``page`` (``--html``), the
    window's speed-up (``--view``; None: no window) and the pictures' ``speedup`` as given."""

    pictures: Pictures
    page: Output | None
    window: float | None
    speedup: float | None

    @property
    def wanted(self) -> bool:
        """Whether anything is drawn: then the replayed run's ticks are kept."""
        return self.pictures.wanted or self.page is not None or self.window is not None


@main.command()
@click.argument("log", type=click.Path(path_type=Path))
@path_option("--plot", help="Draw the path in the maze (PNG).")
@path_option("--plot-signals", help="Draw the signals (PNG).")
@path_option("--gif", help="Animate the run.")
@viewer_options
@click.option("--partial", is_flag=True, help="Replay a damaged log up to its first damaged line.")
@path_option(
    "--mission",
    metavar="CHANGED.yaml",
    help="What if: re-tick this mission's tree against the recorded readings, stopping where it commands differently.",
)
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="What if: change a mission parameter.")
@click.option(
    "--continue",
    "continue_in",
    type=click.Choice(["sim"]),
    default=None,
    help="What if: go on in the simulator from the recorded state where the tree decides differently.",
)
@path_option("--report", help="What if: write the run report, with its counterfactual section (JSON).")
@path_option("--log", "log_out", help="What if: write the replayed run's log.")
@path_option(
    "--html",
    help="Write the run as one HTML page to scrub through; what if: the recorded and the re-ticked run, "
    "their divergence marked.",
)
def replay(
    log: Path,
    plot: Path | None,
    plot_signals: Path | None,
    gif: Path | None,
    view: bool,
    speedup: float | None,
    partial: bool,
    mission: Path | None,
    sets: tuple[str, ...],
    continue_in: str | None,
    report: Path | None,
    log_out: Path | None,
    html: Path | None,
) -> None:
    """Redraw a run from its --log FILE.jsonl without re-running it; with --mission or --set, re-tick
    a changed tree against it (what if)."""
    from thymio_bt.logs import read_log

    pictures = Pictures(plot, plot_signals, gif)
    try:
        if view:
            from thymio_bt.viz.display import require_display

            require_display("without a display, draw the log to files: --plot run.png, --gif run.gif (or .mp4)")
        pictures.check()
        page = Output(html, "--html", stdout_ok=False) if html is not None else None
        drawn = Drawn(pictures, page, (1.0 if speedup is None else speedup) if view else None, speedup)
        if mission is not None or sets or continue_in or report is not None or log_out is not None:
            _what_if(log, mission, sets, continue_in is not None, report, log_out, drawn)
        recording = read_log(log, partial)
        damage_note(log, recording)
        _replay_summary(recording)
        if not (pictures.wanted or view or page):
            click.echo(
                "nothing to draw (hint: --view, --html FILE.html, --plot FILE.png, --plot-signals FILE.png "
                "or --gif FILE.gif)",
                err=True,
            )
        pictures.draw(recording, 4.0 if speedup is None else speedup, quiet=False)
        if page is not None:
            from thymio_bt.viz.page import write_page

            click.echo(f"wrote {write_page([recording], page.path)}", err=True)
        if view:
            from thymio_bt.viz.window import replay as replay_in_window

            replay_in_window(recording, 1.0 if speedup is None else speedup)
    except UserError as exc:
        fail(exc)


def _what_if(
    log: Path,
    mission: Path | None,
    sets: tuple[str, ...],
    continue_sim: bool,
    report: Path | None,
    log_out: Path | None,
    drawn: Drawn,
) -> NoReturn:
    """``replay LOG --mission CHANGED.yaml``: re-tick the changed tree against the log, say where it
    decided differently, write the report, log, pictures and page asked for, show the re-ticked run
    in the window (``--view``), exit as ``run`` does."""
    from thymio_bt.cli.comparing import read_whole
    from thymio_bt.logs.recording import Recorder
    from thymio_bt.mission import load_mission
    from thymio_bt.run.result import RunStatus
    from thymio_bt.run.whatif import COMMAND_TOLERANCE, what_if

    report_out = Output(report, "--report") if report is not None else None
    if log_out is not None and str(log_out) != STDOUT:
        check_writable(log_out, "--log")
    recording = read_whole(log)
    if mission is None and not recording.mission:
        raise UserError(f"{log} does not name its mission (hint: --mission FILE.yaml)")
    spec = load_mission(mission if mission is not None else recording.mission, parse_overrides(sets))
    recorder = Recorder(log_path=log_out, keep=drawn.wanted, statuses=True)
    replayed = what_if(recording, spec, continue_sim=continue_sim, on_tick=recorder)
    result = replayed.result
    err = STDOUT in (str(report), str(log_out))
    out = replayed.counterfactual()
    click.echo(f"{result.mission}: {result.status} after {result.sim_time:.1f} s, {result.ticks} ticks", err=err)
    if result.reason:
        click.echo(f"  reason: [{result.code}] {result.reason}", err=err)
    if replayed.divergence is None and replayed.tolerance > COMMAND_TOLERANCE:
        said = f"within {replayed.tolerance:g} (this log's numbers are rounded): the verdict is as close"
        click.echo(f"  the tree commanded what the recorded run did at every tick, {said}", err=err)
    elif replayed.divergence is None:
        click.echo("  the tree commanded what the recorded run did at every tick: the verdict is exact", err=err)
    for note in replayed.notes:
        click.echo(f"  {note}", err=err)
    click.echo(f"  replayed ticks: {out['replayed_ticks']}, simulated ticks: {out['simulated_ticks']}", err=err)
    if report_out is not None:
        report_out.write_text(json_text(replayed.report()))
    replayed_run = recorder.finish(result)
    drawn.pictures.draw(replayed_run, 4.0 if drawn.speedup is None else drawn.speedup, quiet=False)
    if drawn.page is not None:
        from thymio_bt.viz.page import write_runs

        runs, divergence = what_if_page(recording, replayed_run, replayed)
        click.echo(f"wrote {write_runs(runs, drawn.page.path, divergence)}", err=True)
    if drawn.window is not None:
        from thymio_bt.viz.window import replay as replay_in_window

        replay_in_window(replayed_run, drawn.window)
    sys.exit(0 if result.status is RunStatus.SUCCESS else 1)


def what_if_page(
    recorded: Recording, replayed_run: Recording, replayed: WhatIf
) -> tuple[list[dict[str, Any]], dict[str, Any] | None]:
    """The page of a what-if replay: the recorded run and the re-ticked one as two runs (the second
    with ``simulated_from``, the time its first simulated tick, where ``--continue sim`` took over),
    and the tick where the tree first commanded differently as their divergence."""
    from thymio_bt.viz.page_data import page_data

    new = page_data(replayed_run, "what if")
    simulated = replayed.simulated_ticks
    if simulated and len(replayed_run.samples) >= simulated:
        new["simulated_from"] = replayed_run.samples[-simulated]["t"]
    found = replayed.divergence
    divergence = None if found is None else {"time": found.time, "tick": found.tick, "reason": found.text}
    return [page_data(recorded, "recorded"), new], divergence


def _replay_summary(recording: Recording) -> None:
    """The logged run's summary, as ``run`` prints it: status, time, ticks, final pose, collisions,
    and where and why it did not succeed."""
    end = recording.end
    status = end.get("status") or "UNFINISHED"  # a damaged log read with --partial has no end
    ticks = end.get("ticks", len(recording.samples))
    records = f" ({end['records']} status records)" if "records" in end else ""
    click.echo(f"{recording.mission}: {status} after {end.get('sim_time', 0):.1f} s simulated, {ticks} ticks{records}")
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
        if recording.samples and "cmd" not in recording.samples[0]:  # a .btlog: statuses, no robot
            raise UserError(f"{log} holds node statuses only, no robot (hint: export the run's .jsonl or .mcap log)")
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
        # the records as read_log parsed them, in the log formats' shapes
        writer.header(recording.header)
        for sample in recording.samples:
            writer.tick(sample)
        writer.end({**recording.end, "events": recording.events})
    finally:
        writer.close()


def damage_note(log: Path, recording: Recording) -> None:
    """Say where a ``--partial`` read of ``log`` stopped (nothing when the log was whole)."""
    line = recording.header.get("damaged_at")
    if line:
        click.echo(f"{log}:{line}: damaged line; kept the {len(recording.samples)} ticks before it", err=True)
