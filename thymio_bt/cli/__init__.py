"""The ``thymio-bt`` command line (click). Heavy imports live inside the commands that need them.

Exit codes: 0 success, 1 mission FAILURE or time limit, 2 user error (one clear message, no traceback).
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from functools import partial
from pathlib import Path
from typing import Any, NoReturn

import click

from thymio_bt.errors import UserError
from thymio_bt.outputs import STDOUT, Output, check_writable
from thymio_bt.run.interrupts import Interrupts


def _fail(exc: UserError) -> NoReturn:
    for problem in exc.problems:
        click.echo(f"error: {problem}", err=True)
    if len(exc.problems) > 1:
        click.echo(f"{len(exc.problems)} problems", err=True)
    sys.exit(2)


class _Positive(click.ParamType):
    """A finite number > 0 (click's FloatRange lets NaN through: every comparison with it is false)."""

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number", param, ctx)
        if not (math.isfinite(number) and 0 < number <= 1e9):
            self.fail(f"{value} must be a finite number > 0", param, ctx)
        return number


POSITIVE = _Positive()


def _overrides(values: tuple[str, ...]) -> dict[str, str]:
    return _pairs(values, "--set", "cruise=0.15")


def _pairs(values: tuple[str, ...], option: str, example: str) -> dict[str, str]:
    """``NAME=VALUE`` arguments of a repeatable option, as a dict."""
    out = {}
    for item in values:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise UserError(f"{option} expects NAME=VALUE, got '{item}' (hint: {option} {example})")
        out[name.strip()] = value.strip()
    return out


class _Commands(click.Group):
    """The command group; a Ctrl-C outside a run's own handling (or a second one) exits 130, quietly."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            click.echo("\ninterrupted", err=True)
            sys.exit(130)


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="thymio-bt")
@click.option(
    "--color",
    "--colour",
    "color",
    type=click.Choice(["auto", "always", "never"]),
    default="auto",
    show_default=True,
    help="Colour in the output; auto: on a terminal, unless NO_COLOR is set.",
)
@click.pass_context
def main(ctx: click.Context, color: str) -> None:
    """YAML behaviour-tree missions for a simulated Thymio II (no ROS, no Gazebo)."""
    if color == "always":
        ctx.color = True
    elif color == "never" or os.environ.get("NO_COLOR"):  # https://no-color.org: any non-empty value
        ctx.color = False


def _json(data: Any) -> str:
    return json.dumps(data, indent=1, allow_nan=False) + "\n"


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@click.option(
    "--seed",
    type=click.IntRange(0, 2**63 - 1),
    default=None,
    help="Random seed (noise models), >= 0; default: the mission's.",
)
@click.option(
    "--set",
    "sets",
    multiple=True,
    metavar="NAME=VALUE",
    help="Override a mission parameter, e.g. --set cruise=0.15 or --set noise.wheel=0.03.",
)
@click.option("--maze", type=click.Path(path_type=Path), default=None, help="Run in another maze file.")
@click.option("--start", default=None, metavar="X,Y,YAW", help="Override the start pose, e.g. 0.5,0.3,pi/2.")
@click.option("--report", type=click.Path(path_type=Path), default=None, help="Write the run report (JSON).")
@click.option("--quiet", "-q", is_flag=True, help="Print nothing; use the exit code.")
@click.option(
    "--realtime",
    type=POSITIVE,
    default=None,
    metavar="FACTOR",
    help="Pace the run against the wall clock (1 = real time).",
)
@click.option("--plot", type=click.Path(path_type=Path), default=None, help="Draw the path in the maze (PNG).")
@click.option(
    "--plot-signals",
    type=click.Path(path_type=Path),
    default=None,
    help="Draw pose, speeds and proximity over time (PNG).",
)
@click.option(
    "--gif", type=click.Path(path_type=Path), default=None, help="Animate the run (.gif, or .mp4 with ffmpeg)."
)
@click.option(
    "--view", is_flag=True, help="Watch the run in a window (pygame): SPACE pause, N step, +/- speed, Q quit."
)
@click.option(
    "--speedup", type=POSITIVE, default=None, help="Speed-up of --view (default 1: real time) and --gif (default 4)."
)
@click.option(
    "--log",
    "log",
    type=click.Path(path_type=Path),
    default=None,
    help="Write one JSON object per tick (JSON lines), for 'thymio-bt replay'.",
)
@click.option("--live-tree", is_flag=True, help="Print the tree with statuses whenever it changes.")
@click.option(
    "--backend",
    "backend",
    default=None,
    metavar="NAME",
    help="Where the mission runs: sim (default: the pymunk simulation) or another backend "
    "(see 'thymio-bt backends'); default: the mission's backend: block, else sim.",
)
@click.option(
    "--backend-opt",
    "backend_opts",
    multiple=True,
    metavar="KEY=VALUE",
    help="A setting of the backend, e.g. --backend-opt device=/dev/ttyACM0 (repeatable).",
)
@click.option(
    "--robot",
    default=None,
    metavar="NAME",
    help="The robot model: course (default), enki or real (see 'thymio-bt backends').",
)
@click.option(
    "--groot2",
    type=click.IntRange(1, 65534),
    is_flag=False,
    flag_value=1667,
    default=None,
    metavar="[PORT]",
    help="Serve the live tree to Groot2 on 127.0.0.1:PORT and PORT+1 "
    "(default 1667; use with --realtime; needs thymio-bt[groot2]).",
)
def run(
    mission: Path,
    seed: int | None,
    sets: tuple[str, ...],
    maze: Path | None,
    start: str | None,
    report: Path | None,
    quiet: bool,
    realtime: float | None,
    plot: Path | None,
    plot_signals: Path | None,
    gif: Path | None,
    view: bool,
    speedup: float | None,
    log: Path | None,
    live_tree: bool,
    backend: str | None,
    backend_opts: tuple[str, ...],
    robot: str | None,
    groot2: int | None,
) -> None:
    """Run MISSION (a YAML file) and print a summary."""
    try:
        from thymio_bt.mission import load_mission
        from thymio_bt.run.runner import Run

        overrides = _overrides(sets)
        if robot is not None:
            overrides["robot"] = robot
        report_out = Output(report, "--report") if report is not None else None
        _check_pictures(plot, plot_signals, gif)
        if log is not None and str(log) != STDOUT:
            check_writable(log, "--log")
        spec = load_mission(mission, overrides, maze=maze, start=start)
        device = _backend(spec, seed, backend, backend_opts)
        try:
            runner = Run(spec, seed, backend=device)
        except BaseException:
            device.close()  # the run never started: release the robot now
            raise
        hooks: list[Any] = [_Progress(spec.time_limit, enabled=not quiet and sys.stderr.isatty())]
        recorder = None
        if plot or plot_signals or gif or log:
            from thymio_bt.logs.recording import Recorder

            recorder = Recorder(log_path=log, keep=bool(plot or plot_signals or gif))
            hooks.append(recorder)
        if live_tree:
            from thymio_bt.viz.terminal import LiveTree

            hooks.append(LiveTree())
        window = None
        if view:
            from thymio_bt.viz.window import live_hook

            window = live_hook(runner, 1.0 if speedup is None else speedup)
            hooks.append(window)
        monitor = None
        if groot2 is not None:
            from thymio_bt.viz.groot2 import Groot2Server

            monitor = Groot2Server(groot2)
            hooks.append(monitor)
        try:
            with Interrupts() as interrupts:
                result = runner.run(
                    on_tick=lambda r: [hook(r) for hook in hooks], realtime=realtime, interrupts=interrupts
                )
        finally:
            if monitor is not None:
                monitor.close()
        hooks[0].done()
        if report_out is not None:
            report_out.write_text(_json(result.report()))
        if recorder is not None:
            recording = recorder.finish(result)
            _pictures(recording, plot, plot_signals, gif, 4.0 if speedup is None else speedup, quiet)
    except UserError as exc:
        _fail(exc)
    if not quiet:
        _summary(result, err=STDOUT in (str(report), str(log)))  # stdout carries the report or log
        if result.status != "SUCCESS":
            from thymio_bt.viz.terminal import failing_tree

            click.echo(failing_tree(runner), err=True)
    if interrupts.signal:
        sys.exit(interrupts.exit_code)
    if window is not None:
        window.finish(result)  # with a display: stays open on the last frame until closed
    sys.exit(0 if result.status == "SUCCESS" else 1)


def _backend(spec: Any, seed: int | None, name: str | None, opts: tuple[str, ...]) -> Any:
    """The backend the run asked for (``--backend`` over the mission's), connected and ready."""
    from thymio_bt.backends import backend_kind

    options = dict(spec.backend_options) if name is None or name == spec.backend else {}
    options.update(_pairs(opts, "--backend-opt", "device=/dev/ttyACM0"))
    kind = backend_kind(name or spec.backend)
    return kind.create(spec, spec.seed if seed is None else seed, options)


#: what --plot/--plot-signals (matplotlib) and --gif (Pillow, or ffmpeg for .mp4) can write
PICTURE_SUFFIXES = {
    "--plot": (".png", ".svg", ".pdf", ".jpg"),
    "--plot-signals": (".png", ".svg", ".pdf", ".jpg"),
    "--gif": (".gif", ".mp4"),
}


def _check_pictures(plot: Path | None, plot_signals: Path | None, gif: Path | None) -> None:
    """Refuse, before the run, a picture whose format cannot be written or whose folder is missing."""
    for option, path in (("--plot", plot), ("--plot-signals", plot_signals), ("--gif", gif)):
        if path is None:
            continue
        suffixes = PICTURE_SUFFIXES[option]
        if path.suffix.lower() not in suffixes:
            raise UserError(
                f"{option} {path}: cannot write '{path.suffix or 'no extension'}' (hint: use {', '.join(suffixes)})"
            )
        check_writable(path, option)


def _pictures(
    recording: Any, plot: Path | None, plot_signals: Path | None, gif: Path | None, speedup: float, quiet: bool
) -> None:
    if not (plot or plot_signals or gif):
        return
    from thymio_bt.viz import plots

    for path, draw in ((plot, plots.plot_run), (plot_signals, plots.plot_signals)):
        if path is not None:
            draw(recording, path)
            if not quiet:
                click.echo(f"wrote {path}", err=True)
    if gif is not None:
        plots.animate(recording, gif, speedup=speedup)
        if not quiet:
            click.echo(f"wrote {gif}", err=True)


@main.command()
@click.argument("log", type=click.Path(path_type=Path))
@click.option("--plot", type=click.Path(path_type=Path), default=None, help="Draw the path in the maze (PNG).")
@click.option("--plot-signals", type=click.Path(path_type=Path), default=None, help="Draw the signals (PNG).")
@click.option("--gif", type=click.Path(path_type=Path), default=None, help="Animate the run.")
@click.option(
    "--view", is_flag=True, help="Watch the run in a window (pygame): SPACE pause, N step, +/- speed, Q quit."
)
@click.option(
    "--speedup", type=POSITIVE, default=None, help="Speed-up of --view (default 1: real time) and --gif (default 4)."
)
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

    try:
        _check_pictures(plot, plot_signals, gif)
        recording = read_log(log, partial)
        _damage_note(log, recording)
        end = recording.end
        click.echo(
            f"{recording.mission}: {end.get('status')} after {end.get('sim_time', 0):.1f} s simulated, "
            f"{len(recording.samples)} ticks; final pose {end.get('final_pose')}"
        )
        if not (plot or plot_signals or gif or view):
            click.echo(
                "nothing to draw (hint: --view, --plot FILE.png, --plot-signals FILE.png or --gif FILE.gif)", err=True
            )
        _pictures(recording, plot, plot_signals, gif, 4.0 if speedup is None else speedup, quiet=False)
        if view:
            from thymio_bt.viz.window import replay as replay_in_window

            replay_in_window(recording, 1.0 if speedup is None else speedup)
    except UserError as exc:
        _fail(exc)


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@click.option("--dot", "fmt", flag_value="dot", help="Write a Graphviz .dot file.")
@click.option("--svg", "fmt", flag_value="svg", help="Write an SVG (needs Graphviz's dot program).")
@click.option("--png", "fmt", flag_value="png", help="Write a PNG (needs Graphviz's dot program).")
@click.option(
    "--output",
    "-o",
    type=click.Path(path_type=Path),
    default=None,
    help="File to write (- = standard output); its suffix picks the format when no flag does. "
    "Default with a format flag: MISSION's name with that suffix, in the current folder.",
)
@click.option(
    "--btcpp",
    type=click.Path(path_type=Path),
    default=None,
    metavar="OUT.xml",
    help="Write the tree as BehaviorTree.CPP v4 XML (Groot2 opens it) instead of a drawing.",
)
@click.option("--plugins", is_flag=True, help="Import the mission's plugins (runs their code; default: read only).")
def tree(mission: Path, fmt: str | None, output: Path | None, btcpp: Path | None, plugins: bool) -> None:
    """Print the tree of MISSION; write it as .dot/.svg/.png or BT.CPP XML when asked."""
    try:
        if btcpp is not None:
            from thymio_bt.mission import load_mission
            from thymio_bt.mission.btcpp import mission_xml

            out = Output(btcpp, "--btcpp")
            out.write_text(mission_xml(load_mission(mission, run_plugins=plugins), btcpp))
            if not out.is_stdout:
                click.echo(f"wrote {out}", err=True)
            return
        from thymio_bt.viz.terminal import export_tree, tree_text

        if fmt is None and output is not None:
            fmt = output.suffix.lower().lstrip(".")
            if fmt not in ("dot", "svg", "png"):
                raise UserError(
                    f"--output {output}: cannot tell the format from '{output.suffix or 'no extension'}' "
                    f"(hint: end the name with .dot, .svg or .png, or add --dot/--svg/--png)"
                )
        if fmt is None:
            click.echo(tree_text(mission, plugins))
            return
        out = Output(output if output is not None else Path(mission.stem).with_suffix(f".{fmt}"), "--output")
        if not out.is_stdout:
            click.echo(tree_text(mission, plugins))
        export_tree(mission, out, fmt, plugins)
        if not out.is_stdout:
            click.echo(f"wrote {out}", err=True)
    except UserError as exc:
        _fail(exc)


@main.command()
@click.argument("log", type=click.Path(path_type=Path))
@click.option(
    "--output",
    "-o",
    type=click.Path(path_type=Path),
    default=None,
    help="The log to write; its suffix picks the format (.jsonl, .mcap, .btlog, or a folder: rosbag2).",
)
@click.option(
    "--btlog",
    type=click.Path(path_type=Path),
    default=None,
    metavar="OUT.btlog",
    help="Write a Groot2 log (BT.CPP's FileLogger2 file).",
)
@click.option("--partial", is_flag=True, help="Export a damaged log up to its first damaged line.")
def export(log: Path, output: Path | None, btlog: Path | None, partial: bool) -> None:
    """Convert the run log LOG into another format (e.g. a JSON-lines log into a rosbag2 .mcap)."""
    try:
        from thymio_bt.logs import open_writer, read_log

        targets = [p for p in (output, btlog) if p is not None]
        for target, option in ((output, "--output"), (btlog, "--btlog")):
            if target is not None and str(target) != STDOUT:
                check_writable(target, option)
        if not targets:
            raise UserError("nothing to write (hint: -o run.mcap, or --btlog run.btlog)")
        recording = read_log(log, partial)
        _damage_note(log, recording)
        if not recording.header.get("tree"):
            raise UserError(
                f"{log} was written before logs carried their tree (hint: run the mission again "
                f"with --log to export it)"
            )
        for target in targets:
            writer = open_writer(target)
            try:
                writer.header(recording.header)  # type: ignore[arg-type]
                for sample in recording.samples:
                    writer.tick(sample)  # type: ignore[arg-type]
                writer.end({**recording.end, "events": recording.events})  # type: ignore[typeddict-item]
            finally:
                writer.close()
            click.echo(f"wrote {target}", err=True)
    except UserError as exc:
        _fail(exc)


def _damage_note(log: Path, recording: Any) -> None:
    """Say where a --partial read stopped."""
    line = recording.header.get("damaged_at")
    if line:
        click.echo(f"{log}:{line}: damaged line; kept the {len(recording.samples)} ticks before it", err=True)


class _Progress:
    """A one-line progress indicator on stderr for runs that take more than a second."""

    def __init__(self, limit: float, enabled: bool) -> None:
        self.limit, self.enabled = limit, enabled
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, run: Any) -> None:
        if self.enabled and run.ticks % 20 == 0 and time.perf_counter() - self.start > 1.0:
            t = run.backend.time()
            click.echo(f"\r  simulated {t:7.1f} s of at most {self.limit:g} s", err=True, nl=False)
            self.shown = True

    def done(self) -> None:
        if self.shown:
            click.echo("\r" + " " * 60 + "\r", err=True, nl=False)


def _summary(result: Any, err: bool = False) -> None:
    echo = partial(click.echo, err=err)
    colour = {"SUCCESS": "green", "FAILURE": "red", "TIMEOUT": "yellow", "INTERRUPTED": "yellow"}[result.status]
    rtf = result.real_time_factor
    echo(
        f"{result.mission}: "
        + click.style(result.status, fg=colour, bold=True)
        + f" after {result.sim_time:.1f} s simulated, {result.ticks} ticks "
        f"({result.wall_time:.3f} s wall, {rtf:,.0f}x real time)"
    )
    pose = result.final_pose
    if pose:
        echo(f"  final pose: x={pose['x']:.4f} m  y={pose['y']:.4f} m  yaw={math.degrees(pose['yaw']):.2f} deg")
    else:
        echo("  final pose: no robot")
    clearance = f"{result.min_clearance:.4f} m" if result.min_clearance is not None else "n/a"
    echo(f"  collisions: {result.collisions}   min clearance: {clearance}")
    if result.status != "SUCCESS":
        echo(f"  failed at: {result.failed_path}", err=True)
        echo(f"  reason: [{result.code}] {result.reason}", err=True)


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@click.option("--runs", type=click.IntRange(1, 1_000_000), default=100, show_default=True, help="Number of runs.")
@click.option(
    "--seed-start", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True, help="Seed of the first run."
)
@click.option("--out", type=click.Path(path_type=Path), default=None, help="Write the sweep JSON here.")
@click.option(
    "--set",
    "sets",
    multiple=True,
    metavar="NAME=VALUE",
    help="Override a parameter or a noise model (e.g. --set noise.wheel=0.05).",
)
@click.option("--maze", type=click.Path(path_type=Path), default=None, help="Run in another maze file.")
@click.option("--start", default=None, metavar="X,Y,YAW", help="Override the start pose.")
@click.option("--workers", type=click.IntRange(1, 256), default=None, help="Processes (default: all cores).")
@click.option(
    "--dask",
    "dask",
    default=None,
    metavar="ADDRESS",
    help="Run on a Dask cluster, e.g. tcp://127.0.0.1:8786 (needs thymio-bt[dask]).",
)
@click.option(
    "--matrix",
    "matrix",
    multiple=True,
    metavar="NAME=V1,V2,...",
    help="Sweep every combination of these settings, e.g. --matrix robot=course,enki,real.",
)
def sweep(
    mission: Path,
    runs: int,
    seed_start: int,
    out: Path | None,
    sets: tuple[str, ...],
    maze: Path | None,
    start: str | None,
    workers: int | None,
    dask: str | None,
    matrix: tuple[str, ...],
) -> None:
    """Run MISSION many times with seeds S, S+1, ... and the noise models on; print the statistics."""
    from thymio_bt.run.sweep import LocalPool
    from thymio_bt.run.sweep import sweep as run_sweep

    try:
        sweep_out = Output(out, "--out") if out is not None else None
        executor = _dask(dask) if dask else None
        if matrix:
            _matrix(mission, runs, seed_start, sweep_out, sets, maze, start, executor, workers, matrix)
            return
        with Interrupts() as interrupts:
            with click.progressbar(
                length=runs, label=f"{mission.name}: {runs} runs", file=sys.stderr, show_pos=True
            ) as bar:
                result = run_sweep(
                    mission,
                    runs,
                    seed_start,
                    _overrides(sets),
                    str(maze) if maze else None,
                    start,
                    executor=executor or LocalPool(workers, interrupts),
                    progress=lambda _: bar.update(1),
                    interrupts=interrupts,
                )
            click.echo("", err=True)  # the bar leaves its line open
        data = result.to_json()
        if sweep_out is not None:
            sweep_out.write_text(_json(data))
    except UserError as exc:
        _fail(exc)
    _sweep_table(data, err=sweep_out is not None and sweep_out.is_stdout)
    if interrupts.signal:
        sys.exit(interrupts.exit_code)
    if data["interrupted"]:
        sys.exit(1)  # a worker died: the sweep did not complete


def _matrix(
    mission: Path,
    runs: int,
    seed_start: int,
    out: Output | None,
    sets: tuple[str, ...],
    maze: Path | None,
    start: str | None,
    executor: Any,
    workers: int | None,
    specs: tuple[str, ...],
) -> None:
    """sweep --matrix: one sweep per combination of settings, then one table."""
    from thymio_bt.run.matrix import parse_axes, run_matrix
    from thymio_bt.run.sweep import LocalPool

    axes = parse_axes(specs)
    count = math.prod(len(v) for v in axes.values())
    with Interrupts() as interrupts:
        with click.progressbar(
            length=runs * count, label=f"{mission.name}: {count} cells x {runs} runs", file=sys.stderr, show_pos=True
        ) as bar:
            cells = run_matrix(
                mission,
                runs,
                axes,
                seed_start,
                _overrides(sets),
                str(maze) if maze else None,
                start,
                executor=executor or LocalPool(workers, interrupts),
                progress=lambda _: bar.update(1),
                interrupts=interrupts,
            )
        click.echo("", err=True)
    rows = [cell.row() for cell in cells]
    if out is not None:
        out.write_text(
            _json(
                {
                    "mission": cells[0].result.mission,
                    "runs": runs,
                    "seed_start": seed_start,
                    "axes": axes,
                    "reference_final_pose": cells[0].reference,
                    "cells": rows,
                }
            )
        )
    echo = partial(click.echo, err=out is not None and out.is_stdout)
    names = list(axes)
    echo(
        f"{cells[0].result.mission}: {runs} noisy runs per cell; final error = distance from the final pose "
        f"of the noise-free run on the course's robot"
    )
    echo(
        "  "
        + "".join(f"{n:>14}" for n in names)
        + f"{'success':>10}{'collided':>10}{'median err':>12}{'max err':>10}  failures"
    )
    for row in rows:
        median, worst = row["final_error_median"], row["final_error_max"]
        echo(
            "  "
            + "".join(f"{row['settings'][n]:>14}" for n in names)
            + f"{100 * row['success_rate']:>9.1f}%{row['runs_with_collision']:>10}"
            + (f"{1000 * median:>10.1f}mm" if median is not None else f"{'-':>12}")
            + (f"{1000 * worst:>8.1f}mm" if worst is not None else f"{'-':>10}")
            + "  "
            + ", ".join(f"{code} {n}" for code, n in row["failures"].items())
        )
    if interrupts.signal:
        sys.exit(interrupts.exit_code)


def _dask(address: str) -> Any:
    """A sweep executor on the Dask cluster at ``address``."""
    try:
        from distributed import Client
    except ImportError:
        raise UserError("--dask needs Dask (hint: pip install 'thymio-bt[dask]')") from None
    from thymio_bt.run.distributed import DaskExecutor

    try:
        return DaskExecutor(Client(address, timeout=5))
    except (OSError, TimeoutError) as exc:
        raise UserError(
            f"--dask {address}: cannot reach the scheduler ({exc}) "
            f"(hint: start one with: dask scheduler; dask worker ADDRESS)"
        ) from None


def _sweep_table(data: dict[str, Any], err: bool = False) -> None:
    echo = partial(click.echo, err=err)
    if stopped := data["interrupted"]:
        why = f"interrupted by {stopped}" if stopped.startswith("SIG") else stopped
        echo(
            f"{data['mission']}: {why} after {data['runs']} of {data['runs_requested']} runs; those are reported",
            err=True,
        )
    echo(
        f"{data['mission']}: {data['successes']}/{data['runs']} succeeded "
        f"({100 * data['success_rate']:.1f} %), seeds {data['seed_start']}..{data['seed_start'] + data['runs_requested'] - 1}, "
        f"noise {', '.join(f'{k}={v:g}' for k, v in data['noise'].items())}"
    )
    echo(f"  {data['wall_time']:.2f} s wall, {data['aggregate_real_time_factor'] or 0:,.0f}x real time in aggregate")
    rows = [("mission time [s]", data["sim_time"], 1.0), ("first stop error [mm]", data["first_stop_error"], 1000.0)]
    echo(f"  {'':22} {'min':>8} {'p5':>8} {'median':>8} {'p95':>8} {'max':>8}")
    for label, dist, scale in rows:
        if dist:
            echo(f"  {label:22} " + " ".join(f"{dist[k] * scale:8.2f}" for k in ("min", "p5", "median", "p95", "max")))
    for code, count in data["failures"].items():
        echo(f"  failures {code}: {count}")
    for r in data["results"]:
        if r["status"] != "SUCCESS":
            echo(f"  seed {r['seed']}: {r['status']} [{r['code']}] {r['failed_path']}: {r['reason']}")
            echo(f"    reproduce: {r['reproduce']}")


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Check missions with these overrides.")
@click.option(
    "--plugins",
    is_flag=True,
    help="Import the missions' plugins to check their nodes' parameters too (runs their code).",
)
def validate(files: tuple[Path, ...], sets: tuple[str, ...], plugins: bool) -> None:
    """Check mission FILES (and the mazes they name) or maze files without running anything
    (not even the missions' plugins, unless --plugins)."""
    bad = 0
    for path in files:
        try:
            click.echo(f"ok: {path} ({_check_file(path, _overrides(sets), plugins)})")
        except UserError as exc:
            bad += 1
            for problem in exc.problems:
                click.echo(f"error: {problem}", err=True)
    sys.exit(2 if bad else 0)


def _check_file(path: Path, overrides: dict[str, str], plugins: bool = False) -> str:
    """Validate one mission or maze file (a maze has ``walls:`` or ``grid:`` and no ``tree:``)."""
    from thymio_bt.errors import Problem
    from thymio_bt.inputs.yamlio import load_yaml
    from thymio_bt.robot.model import COURSE
    from thymio_bt.robot.placement import placement_problem

    micromouse = path.suffix.lower() == ".txt"  # a micromouse contest maze
    data = None if path.suffix.lower() == ".xml" or micromouse else load_yaml(path)  # .xml: a BT.CPP mission
    if micromouse or isinstance(data, dict) and "tree" not in data and ("walls" in data or "grid" in data):
        from thymio_bt.maze import load_maze

        maze = load_maze(path)
        spawns = data.get("spawns") if isinstance(data, dict) and "grid" not in data else None
        problems = [
            Problem(
                f"spawn '{name}' is impossible: {why}",
                str(path),
                *(getattr(spawns, "marks", {}).get(name, (0, 0))),
                f"spawns.{name}",
                "move it into a free cell, away from the walls",
            )
            for name, spawn in maze.spawns.items()
            if (why := placement_problem(maze, COURSE, spawn.pose()))
        ]
        if problems:
            raise UserError(problems)
        goal = f", goal {len(maze.goal)} cell{'s' * (len(maze.goal) != 1)}" if maze.goal else ""
        return (
            f"maze: {len(maze.walls)} walls, {len(maze.obstacles)} obstacles, "
            f"spawns {', '.join(maze.spawns) or 'none'}{goal}"
        )
    from thymio_bt.mission import load_mission

    spec = load_mission(path, overrides, run_plugins=plugins)  # checks the start pose against the maze too
    nodes = sum(1 for _ in spec.tree.walk())
    unchecked = sum(
        1 for n in spec.tree.walk() if n.behaviour and getattr(spec.registry[n.behaviour], "unrun_plugin", False)
    )
    note = f"; {unchecked} plugin node{'s' * (unchecked != 1)} not checked: --plugins imports them" if unchecked else ""
    return f"{nodes} node{'s' * (nodes != 1)}, maze {spec.maze.name}{note}"


def _registry(mission: Path | None) -> Any:
    """The node registry: the installed nodes, plus the ``plugins:`` of ``mission`` when one is given
    (their code runs: that is what naming the mission asks for)."""
    from thymio_bt.mission import default_registry, load_mission

    return default_registry() if mission is None else load_mission(mission).registry


@main.command()
@click.argument("name", required=False)
@click.option(
    "--mission",
    type=click.Path(path_type=Path),
    default=None,
    help="Include the behaviours of this mission's plugins (runs their code).",
)
def behaviours(name: str | None, mission: Path | None) -> None:
    """List the behaviours, or document one (its parameters, units, defaults, ranges)."""
    from thymio_bt.mission.node_docs import behaviour_help, behaviour_list

    try:
        registry = _registry(mission)
    except UserError as exc:
        _fail(exc)
    if name is None:
        click.echo(behaviour_list(registry))
        return
    if name not in registry:
        from thymio_bt.errors import did_you_mean

        _fail(UserError(f"no behaviour named '{name}' (hint: {did_you_mean(name, registry)})"))
    click.echo(behaviour_help(registry[name]))


@main.command("backends")
def backends_command() -> None:
    """List the backends (--backend NAME, with their --backend-opt settings) and robot models (--robot NAME)."""
    from thymio_bt.backends import backend_kinds
    from thymio_bt.robot.model import ROBOTS

    try:
        kinds = backend_kinds()
    except UserError as exc:
        _fail(exc)
    click.echo("backends (--backend NAME --backend-opt KEY=VALUE):")
    for kind in kinds.values():
        click.echo(f"  {kind.name:10} {kind.summary}")
        for key, field in kind.options.model_fields.items():
            default = "" if field.default is None else f" [default {field.default}]"
            click.echo(f"  {'':10}   {key}: {field.description}{default}")
    click.echo("robot models (--robot NAME):")
    for model in ROBOTS.values():
        click.echo(f"  {model.name:10} {model.description}")
    click.echo(f"  {'FILE.yaml':10} a profile measured on your robot by 'thymio-bt calibrate'")


@main.command()
@click.option(
    "--output",
    "-o",
    type=click.Path(path_type=Path),
    default=STDOUT,
    show_default=True,
    help="File to write (- = standard output).",
)
@click.option(
    "--mission",
    type=click.Path(path_type=Path),
    default=None,
    help="Include the behaviours of this mission's plugins (runs their code).",
)
def schema(output: Path, mission: Path | None) -> None:
    """Print the JSON Schema of mission files (for editors with yaml-language-server)."""
    from thymio_bt.mission.schema import mission_schema

    try:
        out = Output(output, "--output")
        out.write_text(json.dumps(mission_schema(_registry(mission)), indent=1) + "\n")
    except UserError as exc:
        _fail(exc)


@main.group()
def maze() -> None:
    """Maze tools."""


@maze.command("import")
@click.argument("world", type=click.Path(path_type=Path))
@click.option(
    "--output",
    "-o",
    type=click.Path(path_type=Path),
    default=STDOUT,
    show_default=True,
    help="Maze YAML to write (- = standard output).",
)
@click.option("--model", default=None, help="Import only this model of the world.")
@click.option("--cell", type=POSITIVE, default=0.18, show_default=True, help="Micromouse: cell size (m).")
@click.option("--wall", type=POSITIVE, default=0.012, show_default=True, help="Micromouse: wall thickness (m).")
@click.option("--post", type=POSITIVE, default=0.012, show_default=True, help="Micromouse: post size (m).")
def maze_import(world: Path, output: Path, model: str | None, cell: float, wall: float, post: float) -> None:
    """Convert a Gazebo classic WORLD file of box walls, or a micromouse contest maze (.txt), into a maze file."""
    import yaml

    try:
        out = Output(output, "--output")
        if world.suffix.lower() == ".txt":
            from thymio_bt.maze.micromouse import read_micromouse

            result = read_micromouse(world, cell, wall, post)
        else:
            from thymio_bt.maze.gazebo import import_world

            result = import_world(world, model)
        text = (
            f"# Made by: thymio-bt maze import {world}"
            + ("" if out.is_stdout else f" -o {output}")
            + "\n"
            + yaml.safe_dump(result.to_yaml_dict(), sort_keys=False)
        )
        out.write_text(text)
    except UserError as exc:
        _fail(exc)
    if not out.is_stdout:
        click.echo(f"wrote {output}: {len(result.walls)} walls", err=True)


@maze.command("export")
@click.argument("maze_file", type=click.Path(path_type=Path))
@click.option(
    "--playground",
    "playground",
    is_flag=True,
    required=True,
    help="As an Aseba Playground world (the only export format so far).",
)
@click.option("--spawn", default=None, help="The robot's place: a spawn of the maze (default: its first).")
@click.option("--robot", default="enki", show_default=True, help="The robot model (its wheel axle is placed).")
@click.option(
    "--port", type=click.IntRange(1, 65535), default=33333, show_default=True, help="The robot's Aseba TCP port."
)
@click.option(
    "--output",
    "-o",
    type=click.Path(path_type=Path),
    default=STDOUT,
    show_default=True,
    help="World file to write (- = standard output).",
)
def maze_export(maze_file: Path, playground: bool, spawn: str | None, robot: str, port: int, output: Path) -> None:
    """Write MAZE_FILE (.yaml, grid or .txt) as an Aseba Playground world with one Thymio."""
    from thymio_bt.backends.playground.world import playground_world
    from thymio_bt.maze.files import load_maze
    from thymio_bt.robot.interface import Pose
    from thymio_bt.robot.model import robot_model

    try:
        out = Output(output, "--output")
        result = load_maze(maze_file)
        names = list(result.spawns)
        if spawn is None and not names:
            raise UserError(f"{maze_file} names no spawn (hint: pass --spawn NAME, or add spawns: to the maze)")
        pose = result.spawn(spawn or names[0])
        world = playground_world(result, Pose(*robot_model(robot).axle_of(pose)), port)
        out.write_text(world.text)
    except UserError as exc:
        _fail(exc)
    if not out.is_stdout:
        click.echo(f"wrote {output}: {len(result.walls)} walls, the robot on port {port}", err=True)


@main.command("calibrate")
@click.option(
    "--backend",
    "backend",
    default="sim",
    show_default=True,
    metavar="NAME",
    help="The robot to measure: playground, aseba (a real Thymio), sim, ... (see 'thymio-bt backends').",
)
@click.option("--backend-opt", "backend_opts", multiple=True, metavar="KEY=VALUE", help="A setting of the backend.")
@click.option(
    "--robot", default="enki", show_default=True, help="The built-in model to start from (course, enki, real)."
)
@click.option(
    "--output", "-o", type=click.Path(path_type=Path), required=True, help="The profile file to write (.yaml)."
)
@click.option("--name", default=None, help="The profile's name (default: the file's name).")
def calibrate_command(backend: str, backend_opts: tuple[str, ...], robot: str, output: Path, name: str | None) -> None:
    """Measure a robot's speed scale, wheel base and proximity response into a profile for --robot.

    The robot faces a wall along a corridor (a simulator builds it; a real robot is placed at the
    printed pose): 2 s straight, a slow approach to 8 mm, a spin. About 25 s in real time.
    """
    import tempfile

    import yaml

    from thymio_bt.mission import load_mission
    from thymio_bt.robot.calibrate import arena, calibrate
    from thymio_bt.robot.model import ROBOTS, robot_model
    from thymio_bt.robot.profile import profile_text

    try:
        out = Output(output, "--output")
        if output.suffix.lower() not in (".yaml", ".yml"):
            raise UserError(f"--output {output}: a profile is a .yaml file (hint: -o my_thymio.yaml)")
        if robot not in ROBOTS:
            from thymio_bt.errors import did_you_mean

            raise UserError(
                f"--robot {robot}: calibrate starts from a built-in model (hint: {did_you_mean(robot, ROBOTS)})"
            )
        with tempfile.TemporaryDirectory() as tmp:
            maze_file = Path(tmp) / "corridor.yaml"
            maze_file.write_text(yaml.safe_dump(arena().to_yaml_dict(), sort_keys=False))
            mission_file = Path(tmp) / "calibrate.yaml"
            mission_file.write_text(
                f"name: calibrate\nmaze: {maze_file}\nstart: start\nrobot: {robot}\n"
                "time_limit: 120\ntree:\n  Stop: {}\n"
            )
            spec = load_mission(mission_file)
            device = _backend(spec, 0, backend, backend_opts)
        try:
            device.request_spawn(device.robot_name, spec.start)
            device.advance(0.0)
            with Interrupts():
                result = calibrate(device, robot_model(robot), spec.maze, say=lambda text: click.echo(text, err=True))
        except ValueError as exc:
            raise UserError(f"calibrate: {exc}") from None
        finally:
            device.close()
        out.write_text(profile_text(result.profile(name or output.stem)))
    except UserError as exc:
        _fail(exc)
    for line in result.summary():
        click.echo(line)
    click.echo(f"wrote {output}: use it with --robot {output}", err=True)


@main.group()
def serve() -> None:
    """Serve our simulation to other tools (ROS 2 nodes)."""


@serve.command("ros2")
@click.option(
    "--maze",
    "maze_ref",
    default="two_parts_maze",
    show_default=True,
    help="The maze: a file, or the name of a shipped maze.",
)
@click.option(
    "--start",
    default=None,
    metavar="X,Y,YAW",
    help="The robot's pose at start (base_link), or a spawn of the maze; default: its first spawn.",
)
@click.option(
    "--speedup", type=POSITIVE, default=1.0, show_default=True, help="Run at real time x this (the course's Gazebo: 1)."
)
@click.option("--robot", default="course", show_default=True, help="The robot model simulated.")
@click.option("--quiet", "-q", is_flag=True, help="Print nothing but errors.")
def serve_ros2(maze_ref: str, start: str | None, speedup: float, robot: str, quiet: bool) -> None:
    """Stand in for the course's Gazebo world: its topics, services, TF and /clock over ROS 2.

    A node written for the course (cmd_vel, odom, the /thymio_*_sensor scans, /spawn_entity,
    /delete_entity) runs against it unchanged; so does 'thymio-bt run MISSION --backend ros2'.
    Ctrl-C stops it.
    """
    from thymio_bt.maze.files import load_maze, resolve_maze
    from thymio_bt.robot.interface import Pose
    from thymio_bt.robot.model import robot_model
    from thymio_bt.robot.placement import placement_problem
    from thymio_bt.run.interrupts import Interrupts

    try:
        model = robot_model(robot)
        world = load_maze(resolve_maze(maze_ref))
        pose = _serve_start(world, start)
        problem = placement_problem(world, model, pose)
        if problem:
            raise UserError(
                f"--start {start or ''}: impossible start pose: {problem} (hint: pick a free pose "
                f"inside the maze{', e.g. one of its spawns: ' + ', '.join(world.spawns) if world.spawns else ''})"
            )
        from thymio_bt.backends.ros2.serve import GazeboStandIn

        stand_in = GazeboStandIn(world, Pose(*pose.as_tuple()), model, speedup)
    except UserError as exc:
        _fail(exc)
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    if not quiet:
        click.echo(
            f"serving {world.name} over ROS 2 (domain {domain}), thymio at x={pose.x:g} y={pose.y:g} "
            f"yaw={pose.yaw:g}, {speedup:g}x real time; Ctrl-C stops",
            err=True,
        )

    def progress(sim_time: float, achieved: float) -> None:
        if not quiet and sys.stderr.isatty():
            click.echo(f"\r  {sim_time:8.0f} s simulated, {achieved:5.2f}x real time", err=True, nl=False)

    try:
        with Interrupts() as interrupts:
            stand_in.run(stop=lambda: interrupts.signal is not None, on_second=progress)
    finally:
        stand_in.close()
    if not quiet:
        click.echo("\nstopped", err=True)


def _serve_start(world: Any, start: str | None) -> Any:
    """The start pose of ``serve``: X,Y,YAW, a spawn of the maze, or the maze's first spawn."""
    from thymio_bt.inputs.units import UnitError, parse_pose
    from thymio_bt.robot.interface import Pose

    if start is None or "," not in start:
        names = list(world.spawns)
        if start is None and not names:
            raise UserError(f"maze '{world.name}' names no spawn (hint: pass --start X,Y,YAW)")
        if start is not None and start not in world.spawns:
            from thymio_bt.errors import did_you_mean

            raise UserError(
                f"--start {start}: maze '{world.name}' has no such spawn (hint: "
                f"{did_you_mean(start, names) if names else 'give X,Y,YAW'})"
            )
        return world.spawn(start or names[0])
    try:
        return Pose(*parse_pose(start))
    except UnitError as exc:
        raise UserError(f"--start {start}: {exc} (hint: e.g. --start 0.5,0.3,pi/2)") from None


if __name__ == "__main__":
    main()
