"""``thymio-bt compare``: two runs of one mission, phase by phase, and where they part ways.

``compare A B`` reads two run logs (any format the project reads); ``compare MISSION --backends
sim,playground`` runs the mission on both backends (same seed, same start) and compares those. The
phase table (:mod:`thymio_bt.run.comparison`) and the first divergence
(:mod:`thymio_bt.run.divergence`) are printed, written as JSON with ``--json`` and drawn with
``--plot``; the exit code is 0 when the runs agree within ``--tolerance``, 1 when not, 2 on bad input.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["compare", "run.jsonl"])
    >>> result.exit_code
    2
    >>> print(result.output, end="")
    error: compare takes two run logs, or a mission with --backends A,B (hint: thymio-bt compare sim.jsonl robot.jsonl)
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from thymio_bt.cli.app import fail, json_text, main, parse_overrides, path_option
from thymio_bt.errors import UserError
from thymio_bt.outputs import Output

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording
    from thymio_bt.run.comparison import Comparison

#: how the table prints each phase value: its unit and the factor from the stored one
UNITS = {"time": ("s", 1.0), "yaw_deg": ("deg", 1.0), "turned_deg": ("deg", 1.0), "position": ("cm", 100.0)}
LENGTH = ("cm", 100.0)


@main.command()
@click.argument("runs", nargs=-1, type=click.Path(path_type=Path))
@click.option(
    "--backends",
    default=None,
    metavar="A,B",
    help="Run MISSION on these two backends, then compare (sim,playground).",
)
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=None, help="The seed of both runs (--backends).")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a mission parameter (--backends).")
@click.option(
    "--tolerance",
    default=None,
    metavar="NAME=VALUE,...",
    help="How far the runs may be apart and agree: position (default 1cm), angle (5deg), gap (1cm), time (0.5s).",
)
@path_option("--json", "json_path", help="Write the phase table and the divergence as JSON.")
@path_option("--plot", help="Overlay the two paths and their front readings (PNG).")
@path_option("--html", help="Write both runs as one HTML page to scrub through, the first divergence marked.")
def compare(
    runs: tuple[Path, ...],
    backends: str | None,
    seed: int | None,
    sets: tuple[str, ...],
    tolerance: str | None,
    json_path: Path | None,
    plot: Path | None,
    html: Path | None,
) -> None:
    """Compare two runs of one mission: A B (two run logs), or MISSION --backends A,B."""
    from thymio_bt.run.comparison import Tolerances, compare

    try:
        tolerances = Tolerances.parse(tolerance)
        json_out = Output(json_path, "--json") if json_path is not None else None
        plot_out = Output(plot, "--plot") if plot is not None else None
        if plot is not None and plot.suffix.lower() != ".png":
            raise UserError(f"--plot {plot}: the plot is a PNG (hint: --plot compare.png)")
        page = Output(html, "--html", stdout_ok=False) if html is not None else None
        names, (a, b) = _runs(runs, backends, seed, sets)
        result = compare(a, b, tolerances)
        _print(result, names)
        if json_out is not None:
            json_out.write_text(json_text(result.to_json()))
        if plot_out is not None:
            with plot_out.staged() as staged:
                plot_comparison(a, b, result, names, staged)
        if page is not None:
            from thymio_bt.cli.viewing import page_divergence
            from thymio_bt.viz.page import write_page

            written = write_page([a, b], page.path, page_divergence(result.divergence), list(names))
            click.echo(f"wrote {written}", err=True)
    except UserError as exc:
        fail(exc)
    sys.exit(0 if result.agree else 1)


def _runs(
    runs: tuple[Path, ...], backends: str | None, seed: int | None, sets: tuple[str, ...]
) -> tuple[tuple[str, str], tuple[Recording, Recording]]:
    """The two recordings to compare, and what to call them."""
    if backends is not None and len(runs) == 1:
        names = tuple(n.strip() for n in backends.split(","))
        if len(names) != 2 or not all(names):
            raise UserError(f"--backends takes two backends, got '{backends}' (hint: --backends sim,playground)")
        return (names[0], names[1]), (_run_on(runs[0], names[0], seed, sets), _run_on(runs[0], names[1], seed, sets))
    if backends is not None or len(runs) != 2:
        raise UserError(
            "compare takes two run logs, or a mission with --backends A,B "
            "(hint: thymio-bt compare sim.jsonl robot.jsonl)"
        )
    return (str(runs[0]), str(runs[1])), (read_whole(runs[0]), read_whole(runs[1]))


def read_whole(path: Path) -> Recording:
    """A log, or what is readable of a damaged one (up to its last whole tick), said on stderr."""
    from thymio_bt.logs import format_for, read_log

    partial = format_for(path, reading=True).partial if path.exists() else False
    recording = read_log(path, partial)
    damaged = recording.header.get("damaged_at")
    if damaged:
        click.echo(f"{path}:{damaged}: damaged line; kept the {len(recording.samples)} ticks before it", err=True)
    elif recording.end.get("status") == "INCOMPLETE":
        last = recording.samples[-1]["t"] if recording.samples else 0.0
        click.echo(f"{path}: the log is cut short; kept its {len(recording.samples)} ticks (to {last:g} s)", err=True)
    return recording


def _run_on(mission: Path, backend: str, seed: int | None, sets: tuple[str, ...]) -> Recording:
    """Run ``mission`` on ``backend``, recorded with every node's status."""
    from thymio_bt.cli.option_values import backend_for
    from thymio_bt.logs.recording import Recorder
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    spec = load_mission(mission, parse_overrides(sets))
    runner = Run(spec, seed, backend=backend_for(spec, seed, backend, ()))  # closed by the run, even unprepared
    recorder = Recorder(statuses=True)
    recorder.begin(runner)
    recording = recorder.finish(runner.run(on_tick=recorder))
    click.echo(f"{backend}: {recording.end['status']} after {recording.end['sim_time']:.1f} s", err=True)
    return recording


def _value(key: str, value: Any) -> str:
    """One phase value with its unit: lengths in cm, angles in degrees, times in seconds."""
    if not isinstance(value, (int, float)):
        return "" if value is None else str(value)
    unit, factor = UNITS.get(key, LENGTH)
    return f"{value * factor:.2f} {unit}"


def _print(result: Comparison, names: tuple[str, str]) -> None:
    """The phase table, the first divergence and the verdict."""
    click.echo(f"A: {names[0]}\nB: {names[1]}")
    click.echo(f"    {'value':<11} {'A':>13} {'B':>13} {'B - A':>11}")
    exceeded = set(result.exceeded)
    for phase in result.phases:
        # the table prints any value by its key: the ends as plain mappings
        a: dict[str, Any] = dict(phase.a or {})
        b: dict[str, Any] = dict(phase.b or {})
        diff = phase.diff or {}
        named = f"{phase.node} #{phase.occurrence}"
        if phase.diff is None:
            click.echo(f"{named} ({a.get('kind') or b.get('kind')}): only in {'A' if phase.b is None else 'B'}  !")
            continue
        click.echo(f"{named} ({a.get('kind')})")
        for key in [k for k in diff if k not in ("x", "y")]:
            mark = "  !" if f"{named}: {key}" in exceeded else ""
            if key == "status":
                click.echo(f"    {key:<11} {a['status']:>13} {b['status']:>13}{mark}")
                continue
            shown = (_value(key, a.get(key)), _value(key, b.get(key)))
            if key == "position":  # where each run was, x,y in m
                shown = (f"{a['x']:.3f},{a['y']:.3f} m", f"{b['x']:.3f},{b['y']:.3f} m")
            row = f"{shown[0]:>13} {shown[1]:>13} {_value(key, diff[key]):>11}"
            click.echo(f"    {key:<11} {row}{mark}")
    found = result.divergence
    if found is None:
        click.echo("no divergence: the trees and poses agree at every tick")
    else:
        click.echo(f"first divergence at {found.time:g} s (tick {found.tick}): {found.reason}")
        for name, doing in (("A", found.a), ("B", found.b)):
            pose = doing.pose
            where = (
                "no robot"
                if pose is None
                else f"({pose['x']:.4f}, {pose['y']:.4f}, {math.degrees(pose['yaw']):.1f} deg)"
            )
            click.echo(f"  {name}: running {', '.join(doing.running) or 'nothing'}; pose {where}")
    if result.agree:
        click.echo("the runs agree within the tolerances")
    else:
        click.echo(f"the runs differ: {len(result.exceeded)} values past the tolerances (marked !)")


def plot_comparison(a: Recording, b: Recording, result: Comparison, names: tuple[str, str], path: Path) -> None:
    """Overlay the two paths in the maze, and the front readings over time, the divergence marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (maze_ax, signal_ax) = plt.subplots(1, 2, figsize=(12, 5.5))
    try:
        for wall in a.maze.walls:
            (x0, y0), (x1, y1) = wall.start, wall.end
            maze_ax.plot([x0, x1], [y0, y1], color="black", linewidth=2)
        for recording, colour, name in ((a, "tab:blue", names[0]), (b, "tab:orange", names[1])):
            for xs, ys in _path_segments(recording):
                maze_ax.plot(xs, ys, color=colour, label=name)
                name = "_"  # one legend entry per run
            ts = [s["t"] for s in recording.samples]
            front = [(s.get("prox") or {}).get("front_center") for s in recording.samples]
            signal_ax.plot(
                ts,
                [math.nan if v is None else v * 100 for v in front],
                color=colour,
                label=names[0 if recording is a else 1],
            )
        found = result.divergence
        if found is not None:
            signal_ax.axvline(found.time, color="red", linestyle="--", label=f"divergence {found.time:g} s")
            for doing in (found.a, found.b):
                if doing.pose is not None:
                    maze_ax.plot(doing.pose["x"], doing.pose["y"], "x", color="red", markersize=10)
        maze_ax.set_aspect("equal")
        maze_ax.set_title("paths (ground truth where logged)")
        maze_ax.legend(loc="best", fontsize=8)
        signal_ax.set_xlabel("time (s)")
        signal_ax.set_ylabel("front_center reading (cm)")
        signal_ax.legend(loc="best", fontsize=8)
        fig.tight_layout()
        fig.savefig(path, dpi=100)
    finally:
        plt.close(fig)


def _path_segments(recording: Recording) -> list[tuple[list[float], list[float]]]:
    """The logged path, broken where the robot was absent (a delete and a respawn)."""
    segments: list[tuple[list[float], list[float]]] = []
    current: tuple[list[float], list[float]] | None = None
    for sample in recording.samples:
        pose = sample.get("pose")
        if pose is None:
            current = None
            continue
        if current is None:
            current = ([], [])
            segments.append(current)
        current[0].append(pose["x"])
        current[1].append(pose["y"])
    return segments
