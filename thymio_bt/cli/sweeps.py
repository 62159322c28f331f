"""``thymio-bt sweep``: a mission run many times with the noise models on, and its statistics.

With ``--matrix`` one sweep per combination of settings (robot models, parameters), then one table.
The runs go to a process pool on this machine, or to a Dask cluster with ``--dask``.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["sweep", "square", "--matrix", "robot"])
    >>> result.exit_code
    2
    >>> print(result.output, end="")
    error: --matrix expects NAME=VALUE,VALUE..., got 'robot' (hint: --matrix robot=course,enki,real)
"""

from __future__ import annotations

import asyncio
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, TypeVar

import click

from thymio_bt.cli.app import (
    coverage_options,
    fail,
    json_text,
    main,
    mission_options,
    parse_overrides,
    path_option,
    workers_or_dask,
)
from thymio_bt.errors import UserError
from thymio_bt.outputs import Output, make_folder
from thymio_bt.run.interrupts import Interrupts

if TYPE_CHECKING:
    from thymio_bt.run.matrix import Cell

T = TypeVar("T")


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@click.option("--runs", type=click.IntRange(1, 1_000_000), default=100, show_default=True, help="Number of runs.")
@click.option(
    "--seed-start", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True, help="Seed of the first run."
)
@path_option("--out", help="Write the sweep JSON here.")
@mission_options(
    set_help="Override a parameter or a noise model (e.g. --set noise.wheel=0.05).",
    start_help="Override the start pose.",
)
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
@coverage_options("Count each node's ticks and results over the runs: the tree's coverage.")
@path_option(
    "--html",
    metavar="DIR",
    help="Write the page of each failed run into DIR (MISSION_seedN.html): the run made again, recorded.",
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
    coverage: bool,
    coverage_tree: Path | None,
    html: Path | None,
) -> None:
    """Run MISSION many times with seeds S, S+1, ... and the noise models on; print the statistics."""
    from thymio_bt.cli.option_values import CoverageRequest
    from thymio_bt.run.sweep import sweep as run_sweep

    covered: CoverageRequest | None = None
    try:
        workers_or_dask(workers, dask)
        sweep_out = Output(out, "--out") if out is not None else None
        if coverage or coverage_tree is not None:
            if matrix:
                raise UserError("--coverage is for one sweep, not a --matrix (hint: sweep one cell with --set)")
            covered = CoverageRequest.checked(coverage_tree)
        if html is not None:
            if matrix:
                raise UserError("--html is for one sweep, not a --matrix (hint: sweep one cell with --set)")
            make_folder(html, "--html", "pages/ (one page per failed run)")
        with dask_executor(dask) as executor:
            request = _Request(mission, runs, seed_start, sets, maze, start, executor, workers)
            request.check(matrix)  # before the progress bar says anything
            if matrix:
                _matrix(request, sweep_out, matrix)
                return
            result, interrupts = request.execute(
                runs,
                f"{mission.name}: {runs} runs",
                lambda overrides, **how: run_sweep(
                    mission, runs, seed_start, overrides, request.maze_ref, start, coverage=covered is not None, **how
                ),
            )
        data = result.to_json()
        if covered is not None and result.coverage is not None:
            covered.done(_conditions(request), result.coverage)
        if sweep_out is not None:
            sweep_out.write_text(json_text(data))
        err = sweep_out is not None and sweep_out.is_stdout
        _sweep_table(data, err=err)
        if html is not None and not interrupts.signal:
            _failed_pages(request, data, html)
    except UserError as exc:
        fail(exc)
    if covered is not None and covered.text:
        click.echo(covered.text, err=err)
    if interrupts.signal:
        _exit(interrupts.exit_code)
    # a worker died, or a run broke (its code raised): the sweep did not complete its measurement
    _exit(1 if data["interrupted"] or data["faulted"] else 0)


def _conditions(request: _Request) -> set[str]:
    """The names of the conditions the sweep's mission can use (its plugins read, not run again)."""
    from thymio_bt.analysis.tree_rules import condition_names
    from thymio_bt.mission import load_mission

    spec = load_mission(
        request.mission, parse_overrides(request.sets), request.maze_ref, request.start, run_plugins=False
    )
    return condition_names(spec.registry)


def _exit(code: int) -> None:
    """Exit with ``code``, even if a plugin left a thread running in this process (``--workers 1``)."""
    from thymio_bt.run.leftovers import end_despite_threads

    end_despite_threads(code)
    sys.exit(code)


class _Request(NamedTuple):
    """What a sweep and each cell of a matrix share: the mission, how many runs from which seed, the
    ``--set``/``--maze``/``--start`` options, and where the runs go (``executor``, else a local pool)."""

    mission: Path
    runs: int
    seed_start: int
    sets: tuple[str, ...]
    maze: Path | None
    start: str | None
    executor: Any
    workers: int | None

    @property
    def maze_ref(self) -> str | None:
        """The ``--maze`` option as the sweep takes it."""
        return str(self.maze) if self.maze else None

    def check(self, matrix: tuple[str, ...]) -> None:
        """Load the mission with the ``--set`` options, and with each value of each ``--matrix``
        axis: a mistake is a :class:`UserError` (said at ``--matrix`` for an axis's value)."""
        from dataclasses import replace

        from thymio_bt.mission import load_mission
        from thymio_bt.run.matrix import parse_axes

        overrides = parse_overrides(self.sets)
        load_mission(self.mission, overrides, self.maze_ref, self.start, run_plugins=False)
        for name, values in parse_axes(matrix).items():
            for value in values:
                try:
                    load_mission(self.mission, {**overrides, name: value}, self.maze_ref, self.start, run_plugins=False)
                except UserError as exc:
                    raise UserError(
                        [replace(p, file="--matrix") if p.file == "--set" else p for p in exc.problems]
                    ) from None

    def execute(self, length: int, label: str, work: Callable[..., T]) -> tuple[T, Interrupts]:
        """``work(overrides, executor=, progress=, interrupts=)`` under a progress bar of ``length`` runs;
        Ctrl-C and SIGTERM stop it cleanly (the runs done are kept)."""
        from thymio_bt.run.sweep import LocalPool

        with Interrupts() as interrupts:
            with click.progressbar(length=length, label=label, file=sys.stderr, show_pos=True) as bar:
                overrides = parse_overrides(self.sets)  # a bad --set is reported under the bar's label
                result = work(
                    overrides,
                    executor=self.executor or LocalPool(self.workers, interrupts),
                    progress=lambda _: bar.update(1),
                    interrupts=interrupts,
                )
            click.echo("", err=True)  # the bar leaves its line open
        return result, interrupts


def _matrix(request: _Request, out: Output | None, specs: tuple[str, ...]) -> None:
    """sweep --matrix: one sweep per combination of settings, then one table."""
    from thymio_bt.run.matrix import parse_axes, run_matrix

    mission, runs, seed_start = request.mission, request.runs, request.seed_start
    axes = parse_axes(specs)
    count = math.prod(len(v) for v in axes.values())
    cells, interrupts = request.execute(
        runs * count,
        f"{mission.name}: {count} cells x {runs} runs",
        lambda overrides, **how: run_matrix(
            mission, runs, axes, seed_start, overrides, request.maze_ref, request.start, **how
        ),
    )
    rows = [cell.row() for cell in cells]
    if out is not None:
        out.write_text(
            json_text(
                {
                    "mission": cells[0].result.mission,
                    "runs": runs,
                    "seed_start": seed_start,
                    "axes": axes,
                    "reference_final_pose": None if cells[0].reference is None else cells[0].reference.as_dict(),
                    "cells": rows,
                }
            )
        )
    _matrix_table(cells, rows, list(axes), runs, err=out is not None and out.is_stdout)
    if interrupts.signal:
        _exit(interrupts.exit_code)
    _exit(1 if any(cell.result.faulted for cell in cells) else 0)


def _matrix_table(cells: list[Cell], rows: list[dict[str, Any]], names: list[str], runs: int, err: bool) -> None:
    """One line per cell of a matrix (its settings, success rate, collisions, final errors, failures)."""
    echo = partial(click.echo, err=err)
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


#: seconds Dask gets to connect to the scheduler (its own timeout, also the Client's)
DASK_TIMEOUT = 5.0
#: seconds the whole question may take: Dask's connection (which retries a refused one for
#: DASK_TIMEOUT s and then says so) and the scheduler's answer
ANSWER_TIMEOUT = 2 * DASK_TIMEOUT


@contextmanager
def dask_executor(address: str | None) -> Iterator[Any]:
    """A sweep executor on the Dask cluster at ``address`` (None without one), its client closed
    after: a client left open keeps reconnecting to a scheduler that has gone."""
    if address is None:
        yield None
        return
    executor = _dask(address)
    try:
        yield executor
    finally:
        executor.client.close()


def _dask(address: str) -> Any:
    """A sweep executor on the Dask cluster at ``address``; an address that is not one, a scheduler
    that cannot be reached or does not answer within :data:`ANSWER_TIMEOUT` s, is a :class:`UserError`."""
    try:
        from distributed import Client
    except ImportError:
        raise UserError("--dask needs Dask (hint: pip install 'thymio-bt[dask]')") from None
    from thymio_bt.run.distributed import DaskExecutor

    hint = "hint: start one with: dask scheduler; dask worker ADDRESS; then --dask tcp://HOST:8786"
    from distributed.comm.addressing import get_address_host_port

    try:
        port = get_address_host_port(address)[1]
    except ValueError as error:
        raise UserError(f"--dask {address}: not a scheduler address: {_said(error)} ({hint})") from None
    if not 0 < port < 65536:
        raise UserError(f"--dask {address}: not a scheduler address: port {port} is not 1-65535 ({hint})")
    # Dask's own timeout covers the connection, not the scheduler's answer, and a Client that never
    # hears one cannot be abandoned (it holds Dask's loop and hangs the process at exit): the
    # scheduler is asked who it is first, on a loop of our own that a timeout cancels cleanly
    try:
        identity = asyncio.run(asyncio.wait_for(_identity(address), ANSWER_TIMEOUT))
    except asyncio.TimeoutError:
        raise UserError(
            f"--dask {address}: no answer from a Dask scheduler within {ANSWER_TIMEOUT:g} s ({hint})"
        ) from None
    except OSError as error:  # refused, unreachable, or Dask's own connection timeout
        raise UserError(f"--dask {address}: cannot reach the scheduler ({_said(error)}) ({hint})") from None
    except Exception as error:  # Dask's handshake, given garbage, raises anything (even MemoryError)
        identity = error
    if not isinstance(identity, dict) or identity.get("type") != "Scheduler":
        raise UserError(f"--dask {address}: the peer answered, but not as a Dask scheduler ({hint})")
    return DaskExecutor(Client(address, timeout=DASK_TIMEOUT))


async def _identity(address: str) -> Any:
    """What the Dask server at ``address`` says it is (a scheduler answers ``{"type": "Scheduler", ...}``)."""
    from distributed.comm import connect

    comm = await connect(address, timeout=DASK_TIMEOUT)
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def _said(exc: BaseException) -> str:
    """An exception's type and message, for a message (its type alone when ``str()`` fails)."""
    try:
        text = str(exc)
    except Exception:
        text = ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _failed_pages(request: _Request, data: dict[str, Any], folder: Path) -> None:
    """``sweep --html DIR``: each failed run of the sweep made again (same mission, settings and seed:
    the same run, bit for bit), recorded, and its page written to ``DIR/MISSION_seedN.html``."""
    from thymio_bt.grade.site import safe_name
    from thymio_bt.logs.recording import Recorder
    from thymio_bt.mission import load_mission
    from thymio_bt.robot.noise import REALISTIC
    from thymio_bt.run.runner import Run
    from thymio_bt.viz.page import write_page

    failed = [r for r in data["results"] if r["status"] != "SUCCESS"]
    if not failed:
        click.echo(f"no failed run: no page written in {folder}", err=True)
        return
    settings = {**REALISTIC.settings(), **parse_overrides(request.sets)}
    spec = load_mission(request.mission, settings, request.maze_ref, request.start)
    for summary in failed:
        seed = summary["seed"]
        recorder = Recorder(statuses=True)
        try:
            recording = recorder.finish(Run(spec, seed).run(on_tick=recorder))
        except Exception as exc:  # a run that broke breaks again: its page cannot be made
            click.echo(f"  seed {seed}: no page, the run raised {_said(exc)}", err=True)
            continue
        name = f"{safe_name(spec.name)}_seed{seed}.html"  # a mission's name is its author's: kept inside DIR
        page = write_page([recording], folder / name, labels=[f"{spec.name} seed {seed}"])
        click.echo(f"  seed {seed}: page {page}", err=True)


def _sweep_table(data: dict[str, Any], err: bool = False) -> None:
    """The statistics of a sweep's JSON ``data``: success rate, times, errors, failures with how to reproduce them."""
    from thymio_bt.run.sweep import FAULTS

    echo = partial(click.echo, err=err)
    if stopped := data["interrupted"]:
        why = f"interrupted by {stopped}" if stopped.startswith("SIG") else stopped
        echo(
            f"{data['mission']}: {why} after {data['runs']} of {data['runs_requested']} runs; those are reported",
            err=True,
        )
    last_seed = data["seed_start"] + data["runs_requested"] - 1
    echo(
        f"{data['mission']}: {data['successes']}/{data['runs']} succeeded "
        f"({100 * data['success_rate']:.1f} %), seeds {data['seed_start']}..{last_seed}, "
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
    if data["faulted"]:
        echo(
            f"{data['mission']}: {data['faulted']} of {data['runs']} runs broke (their code raised: "
            f"{', '.join(FAULTS)}): the sweep is incomplete, exit code 1",
            err=True,
        )
