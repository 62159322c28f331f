"""``thymio-bt run``: one run of a mission, in named steps.

The steps: check the outputs before anything runs (report, log, pictures), load the mission, connect
the backend (:func:`~thymio_bt.cli.option_values.backend_for`) and prepare the run, attach the hooks
that watch it tick by tick (progress line, recorder, live tree, window, Groot2 server), run it, then
write the report and the pictures and print the summary. Exit codes: 0 SUCCESS, 1 any other end, 2 a user error, and the
signal's code (130 for Ctrl-C) when interrupted.
"""

from __future__ import annotations

import gc
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import click

from thymio_bt.cli.app import (
    POSITIVE,
    backend_options,
    clearance_text,
    coverage_options,
    fail,
    json_text,
    main,
    mission_options,
    not_both,
    parse_overrides,
    path_option,
    pose_text,
    viewer_options,
)
from thymio_bt.cli.option_values import CoverageRequest, backend_for
from thymio_bt.cli.pictures import Pictures
from thymio_bt.errors import UserError
from thymio_bt.outputs import STDOUT, Output, check_writable
from thymio_bt.run.interrupts import Interrupts

if TYPE_CHECKING:
    from thymio_bt.btcpp.groot2 import Groot2Server
    from thymio_bt.logs.recording import Recorder, Recording
    from thymio_bt.plan.model import Mission
    from thymio_bt.run.runner import Run, RunResult
    from thymio_bt.viz.live import LiveServer
    from thymio_bt.viz.window import LiveView


#: what ``run`` shows without a display, for ``--view`` refused there
NO_DISPLAY_HINT = (
    "without a display, draw the run to files: --plot run.png, --gif run.gif (or .mp4), "
    "or watch it live in Groot2: --groot2 --realtime 1"
)


#: the slowest ``--realtime`` factor: a simulated second then lasts 11.6 days; below it, the pacing's
#: wait (simulated time / factor) soon overflows what a timestamp can hold
SLOWEST = 1e-6


def web_address(value: str) -> tuple[str, int]:
    """``--web``'s ``[ADDRESS:]PORT`` as (address, port); the address is 127.0.0.1 unless given.

    >>> web_address("8765"), web_address("0.0.0.0:0")
    (('127.0.0.1', 8765), ('0.0.0.0', 0))
    >>> web_address("localhost:http")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    click.exceptions.BadParameter: 'localhost:http' is not [ADDRESS:]PORT (hint: --web 8765, or 0.0.0.0:8765 ...)
    """
    address, _, port = value.rpartition(":")
    if not port.isdigit() or int(port) > 65535:
        raise click.BadParameter(f"{value!r} is not [ADDRESS:]PORT (hint: --web 8765, or 0.0.0.0:8765 in a container)")
    return address or "127.0.0.1", int(port)


def _pacing(factor: float | None) -> float | None:
    """The ``--realtime`` factor, refused below :data:`SLOWEST`.

    >>> _pacing(1e-300)
    Traceback (most recent call last):
    ...
    click.exceptions.BadParameter: 1e-300 is too slow to pace a run (hint: at least 1e-06, e.g. 0.5 for half speed)
    """
    if factor is not None and factor < SLOWEST:
        raise click.BadParameter(
            f"{factor:g} is too slow to pace a run (hint: at least {SLOWEST:g}, e.g. 0.5 for half speed)"
        )
    return factor


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@click.option(
    "--seed",
    type=click.IntRange(0, 2**63 - 1),
    default=None,
    help="Random seed (noise models), >= 0; default: the mission's.",
)
@mission_options(
    set_help="Override a mission parameter, e.g. --set cruise=0.15 or --set noise.wheel=0.03.",
    start_help="Override the start pose, e.g. 0.5,0.3,pi/2.",
)
@path_option("--report", help="Write the run report (JSON).")
@click.option("--quiet", "-q", is_flag=True, help="Print nothing; use the exit code.")
@click.option(
    "--realtime",
    type=POSITIVE,
    default=None,
    metavar="FACTOR",
    callback=lambda ctx, param, value: _pacing(value),
    help=f"Pace the run against the wall clock (1 = real time; at least {SLOWEST:g}).",
)
@path_option("--plot", help="Draw the path in the maze (PNG).")
@path_option("--plot-signals", help="Draw pose, speeds and proximity over time (PNG).")
@path_option("--gif", help="Animate the run (.gif, or .mp4 with ffmpeg).")
@viewer_options
@path_option("--html", help="Write the run as one HTML page to scrub through (see 'thymio-bt view').")
@path_option("--log", "log", help="Write one JSON object per tick (JSON lines), for 'thymio-bt replay'.")
@click.option("--live-tree", is_flag=True, help="Print the tree with statuses whenever it changes.")
@backend_options(
    "Where the mission runs: sim (default: the pymunk simulation) or another backend "
    "(see 'thymio-bt backends'); default: the mission's backend: block, else sim."
)
@click.option(
    "--robot",
    default=None,
    metavar="NAME",
    help="The robot model: course, enki, real or a calibrated profile FILE.yaml; by default the "
    "mission's, else the backend's own (course in the simulation, enki on the Playground, real on a "
    "Thymio; see 'thymio-bt backends').",
)
@coverage_options("Count each node's ticks and results: the tree's coverage, in the report too.")
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
@click.option(
    "--web",
    is_flag=False,
    flag_value="8765",
    default=None,
    metavar="[[ADDRESS:]PORT]",
    callback=lambda ctx, param, value: None if value is None else web_address(value),
    help="Watch the run in a browser: serve its page on 127.0.0.1:PORT (default 8765; 0: any free "
    "port; 0.0.0.0:PORT inside a container) as it goes, paced by --realtime (default 1 with --web).",
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
    html: Path | None,
    log: Path | None,
    live_tree: bool,
    backend: str | None,
    backend_opts: tuple[str, ...],
    robot: str | None,
    coverage: bool,
    coverage_tree: Path | None,
    groot2: int | None,
    web: tuple[str, int] | None,
) -> None:
    """Run MISSION (a YAML file) and print a summary."""
    pictures = Pictures(plot, plot_signals, gif)
    covered: CoverageRequest | None = None
    try:
        if view:
            from thymio_bt.viz.display import require_display

            require_display(NO_DISPLAY_HINT)
        from thymio_bt.mission import load_mission
        from thymio_bt.mission.settings import ROBOT_OPTION

        overrides = parse_overrides(sets)
        if robot is not None:
            overrides[ROBOT_OPTION] = robot  # --set robot=NAME, its problems said at --robot
        report_out = _check_outputs(report, pictures, log)
        page = Output(html, "--html", stdout_ok=False) if html is not None else None
        if coverage or coverage_tree is not None:
            covered = CoverageRequest.checked(coverage_tree)
        spec = load_mission(mission, overrides, maze=maze, start=start)
        runner = _prepare(spec, seed, backend, backend_opts, node_stats=covered is not None)
        # the modules, the mission and the world live until the process ends: the garbage collector's
        # passes leave them out from here on (a tenth of the start-up's and the run's instructions went
        # to walking them again and again, benchmarks/README.md, "The registry imports ...")
        gc.freeze()
        if web is not None and realtime is None:
            realtime = 1.0  # a run watched live goes at the speed of the robot
        hooks = _Hooks(_Progress(spec.time_limit, enabled=not quiet and sys.stderr.isatty()))
        hooks.attach(
            runner,
            log=log,
            keep=pictures.wanted or page is not None,
            statuses=page is not None,
            live_tree=live_tree,
            view=(1.0 if speedup is None else speedup) if view else None,
            groot2=groot2,
            web=web,
        )
        result, interrupts = hooks.watch(runner, realtime)
        if covered is not None:
            from thymio_bt.analysis.tree_rules import condition_names
            from thymio_bt.run.coverage import Coverage

            counts = Coverage.of(spec.tree).add(result.node_stats).to_json()
            covered.done(condition_names(spec.registry), counts, spec.registry)
        if report_out is not None:
            report_out.write_text(json_text(_report(result, covered)))
        if hooks.recorder is not None:
            _draw(hooks.recorder.finish(result), pictures, page, 4.0 if speedup is None else speedup, quiet)
    except UserError as exc:
        fail(exc)
    err = STDOUT in (str(report), str(log))
    _conclude(runner, result, interrupts, hooks.window, quiet, err, covered.text if covered else None)


def _report(result: RunResult, covered: CoverageRequest | None) -> dict[str, Any]:
    """The run report, with the tree's coverage when asked (a key of its own, after the report's)."""
    data = result.report()
    if covered is not None:
        data["coverage"] = covered.data
    return data


def _draw(recording: Recording, pictures: Pictures, page: Output | None, speedup: float, quiet: bool) -> None:
    """The pictures asked for (the animation at ``speedup``) and the ``--html`` page of the run."""
    pictures.draw(recording, speedup, quiet)
    if page is not None:
        from thymio_bt.viz.page import write_page

        write_page([recording], page.path)


def _check_outputs(report: Path | None, pictures: Pictures, log: Path | None) -> Output | None:
    """Refuse, before anything runs, a report, picture or log that cannot be written; the report's output."""
    both = str(report) == STDOUT and str(log) == STDOUT
    not_both("--report -", "--log -", both, "one of them to standard output, the other to a file")
    report_out = Output(report, "--report") if report is not None else None
    pictures.check()
    if log is not None and str(log) != STDOUT:
        check_writable(log, "--log")
    return report_out


def _prepare(
    spec: Mission, seed: int | None, backend: str | None, backend_opts: tuple[str, ...], node_stats: bool = False
) -> Run:
    """The run of ``spec`` on its backend (its nodes counting their ticks when ``node_stats``); the
    backend is released if the run cannot be prepared (by :class:`~thymio_bt.run.runner.Run`)."""
    from thymio_bt.run.runner import Run

    return Run(spec, seed, node_stats=node_stats, backend=backend_for(spec, seed, backend, backend_opts))


class _Hooks:
    """What watches a run tick by tick, called in this order: the progress line, then each of
    ``extra`` (the recorder, the live tree, the window, the Groot2 server, as asked)."""

    def __init__(self, progress: _Progress) -> None:
        self.progress = progress
        self.extra: list[Callable[[Run], None]] = []
        self.recorder: Recorder | None = None
        self.window: LiveView | None = None
        self.monitor: Groot2Server | None = None
        self.live: LiveServer | None = None

    def __call__(self, run: Run) -> None:
        """One tick of ``run``: every hook sees it."""
        self.progress(run)
        for hook in self.extra:
            hook(run)

    def attach(
        self,
        runner: Run,
        log: Path | None,
        keep: bool,
        live_tree: bool,
        view: float | None,
        groot2: int | None,
        statuses: bool = False,
        web: tuple[str, int] | None = None,
    ) -> None:
        """Make the hooks asked for: a recorder when there is a ``log`` to write or samples to ``keep``
        (with the tree's statuses if ``statuses``), a page served live at ``web`` (address, port),
        the ``live_tree``, a window at speed-up ``view`` and a Groot2 server on port ``groot2``."""
        if keep or log is not None:
            from thymio_bt.logs.recording import Recorder

            self.recorder = Recorder(log_path=log, keep=keep, statuses=statuses)
            self.recorder.begin(runner)  # the log's header now: a run stuck in its first tick keeps it
            self.extra.append(self.recorder)
        if live_tree:
            from thymio_bt.viz.terminal import LiveTree

            self.extra.append(LiveTree())
        if view is not None:
            from thymio_bt.viz.window import live_hook

            self.window = live_hook(runner, view)
            self.extra.append(self.window)
        if groot2 is not None:
            from thymio_bt.btcpp.groot2 import Groot2Server

            self.monitor = Groot2Server(groot2)
            self.extra.append(self.monitor)
        if web is not None:
            from thymio_bt.viz.live import LiveServer

            self.live = LiveServer(web[1], web[0])
            self.live.begin(runner)
            click.echo(f"watch the run at {self.live.url}", err=True)
            if web[0] not in ("127.0.0.1", "localhost", "::1"):
                click.echo(f"  (served on {web[0]}: whoever reaches this machine's port {web[1]} can watch)", err=True)
            self.extra.append(self.live)

    def watch(self, runner: Run, realtime: float | None) -> tuple[RunResult, Interrupts]:
        """Run ``runner`` under these hooks (Ctrl-C and SIGTERM end it cleanly); close the Groot2 server
        and the live page's server (once a page watching it has the run's end)."""
        result: RunResult | None = None
        try:
            with Interrupts() as interrupts:
                result = runner.run(on_tick=self, realtime=realtime, interrupts=interrupts)
        finally:
            if self.monitor is not None:
                self.monitor.close()
            if self.live is not None:
                if result is not None:
                    self.live.finish(result)
                self.live.close()
        self.progress.done()
        return result, interrupts


def _conclude(
    runner: Run,
    result: RunResult,
    interrupts: Interrupts,
    window: LiveView | None,
    quiet: bool,
    err: bool,
    coverage: str | None = None,
) -> NoReturn:
    """Print the summary (on stderr when ``err``: stdout carries the report or log) and the tree's
    ``coverage`` when there is one, show the window's last frame, and exit with the run's code."""
    from thymio_bt.run.result import RunStatus

    if not quiet:
        _summary(result, err=err)
        if coverage:
            click.echo(coverage, err=err)
        if result.status is not RunStatus.SUCCESS:
            from thymio_bt.viz.terminal import failing_tree

            click.echo(failing_tree(runner), err=True)
    from thymio_bt.run.leftovers import end_despite_threads

    if interrupts.signal:
        end_despite_threads(interrupts.exit_code)
        sys.exit(interrupts.exit_code)
    if window is not None:
        window.finish(result)  # with a display: stays open on the last frame until closed
    code = 0 if result.status is RunStatus.SUCCESS else 1
    end_despite_threads(code)  # a plugin's thread left running must not keep the process alive
    sys.exit(code)


class _Progress:
    """A one-line progress indicator on stderr for runs that take more than a second."""

    def __init__(self, limit: float, enabled: bool) -> None:
        self.limit, self.enabled = limit, enabled
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, run: Any) -> None:
        """Every 20 ticks after the first second: the simulated time so far, over the line before."""
        if self.enabled and run.ticks % 20 == 0 and time.perf_counter() - self.start > 1.0:
            t = run.backend.time()
            click.echo(f"\r  simulated {t:7.1f} s of at most {self.limit:g} s", err=True, nl=False)
            self.shown = True

    def done(self) -> None:
        """Blank the line, if anything was shown."""
        if self.shown:
            click.echo("\r" + " " * 60 + "\r", err=True, nl=False)


def _summary(result: RunResult, err: bool = False) -> None:
    """The run's status, times, final pose and clearance; where and why it failed, on stderr."""
    from thymio_bt.enums import FailureCode
    from thymio_bt.run.result import RunStatus

    echo = partial(click.echo, err=err)
    colour = {RunStatus.SUCCESS: "green", RunStatus.FAILURE: "red", RunStatus.TIMEOUT: "yellow"}[result.status]
    shown: str = result.status
    if result.code is FailureCode.INTERRUPTED:  # a FAILURE by the report's contract, said as what it was
        colour, shown = "yellow", f"{result.status} (INTERRUPTED)"
    rtf = result.real_time_factor
    echo(
        f"{result.mission}: "
        + click.style(shown, fg=colour, bold=True)
        + f" after {result.sim_time:.1f} s simulated, {result.ticks} ticks "
        f"({result.wall_time:.3f} s wall, {rtf:,.0f}x real time)"
    )
    echo(f"  final pose: {pose_text(result.final_pose_json)}")
    echo(f"  collisions: {result.collisions}   min clearance: {clearance_text(result.min_clearance)}")
    if result.status is not RunStatus.SUCCESS:
        # no node to blame when the run ended outside the tree (time limit, a lost robot, before a tick)
        if result.failed_path is not None:
            echo(f"  failed at: {result.failed_path}", err=True)
        echo(f"  reason: [{result.code}] {result.reason}", err=True)
