"""Run a mission many times with consecutive seeds and the noise models on, in parallel.

The executor boundary is one picklable function, :func:`run_job`, mapped over :class:`Job` s by
anything with ``imap_unordered(fn, iterable)``: the local process pool here, and the same call on
``ray.util.multiprocessing.Pool`` (Ray) or a small adapter over ``dask.distributed.Client.map``
(Dask) to go past one machine. Results are sorted by seed, so the same sweep gives the same table.

Example (three runs in this process; by default one worker per core):

>>> result = sweep("maze_bonus", runs=3, executor=LocalPool(workers=1))
>>> result.success_rate, [r["seed"] for r in result.results], result.noise["wheel"]
(1.0, [0, 1, 2], 0.027)
>>> result.reproduce(1)
'thymio-bt run maze_bonus --set noise.odometry=0.01 --set noise.range_sd=0.001 --set noise.wheel=0.027 --seed 1'
"""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import shlex
import signal
import statistics
import threading
from collections.abc import Callable, Iterable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Protocol, TypedDict

from thymio_bt.errors import ThymioBtError
from thymio_bt.robot.noise import REALISTIC
from thymio_bt.run.interrupts import Interrupted, Interrupts

if TYPE_CHECKING:
    from thymio_bt.plan.model import Mission


@dataclass(frozen=True)
class Job:
    """One run of a sweep: everything a worker needs, picklable."""

    mission: str
    seed: int
    overrides: tuple[tuple[str, str], ...] = ()
    maze: str | None = None
    start: str | None = None
    #: a digest of every file the mission is read from and of the settings: the workers' cache key, so
    #: a file edited between two sweeps (same path) is read again by long-lived (Ray, Dask) workers
    key: str = ""
    #: whether the run's tree coverage comes back with its summary (:mod:`thymio_bt.run.coverage`)
    coverage: bool = False


#: a worker's missions, by :attr:`Job.key` (or, for a job made without one, by what it names)
_CACHE: dict[str | tuple[Any, ...], Mission] = {}

#: the signals a run of :func:`run_job` honours at its next tick: the sweep's own, when its runs are run
#: in its process (one worker), so that a signal ends the run at hand, not after it (or breaks in)
_HONOURED: ContextVar[Interrupts | None] = ContextVar("honoured", default=None)


def content_key(sources: Iterable[Path], *settings: Any) -> str:
    """A digest of the files' contents and the settings (not their paths)."""
    digest = hashlib.sha256(repr(settings).encode())
    for source in sources:
        digest.update(Path(source).read_bytes())
    return digest.hexdigest()


class _Row(TypedDict):
    seed: int
    #: a :class:`~thymio_bt.run.result.RunStatus`, as text once it went through JSON
    status: str
    sim_time: float
    final_pose: dict[str, float] | None
    reason: str | None
    #: a :class:`~thymio_bt.behaviours.base.FailureCode`, or a plugin behaviour's own code
    code: str | None
    failed_path: str | None
    collisions: int
    #: how far from its distance the first MoveUntilWall stopped (m)
    first_stop_error: float | None
    wall_time: float


class SweepRow(_Row, total=False):
    """One run of a sweep, as :func:`run_job` summarises it for the sweep JSON's ``results``; a row
    crosses processes (and a Dask cluster) as it is, a plain dict."""

    #: the run's tree coverage (:meth:`thymio_bt.run.coverage.Coverage.to_json`), when asked for
    coverage: dict[str, Any]


def run_job(job: Job) -> SweepRow:
    """Run one job and summarise it (the function executors map); missions are loaded once per worker.
    With :attr:`Job.coverage`, the summary has the run's ``coverage`` JSON too."""
    from thymio_bt.behaviours.base import describe
    from thymio_bt.enums import FailureCode
    from thymio_bt.mission import load_mission
    from thymio_bt.run.coverage import Coverage
    from thymio_bt.run.runner import Run, RunStatus

    key: str | tuple[Any, ...] = job.key or (job.mission, job.overrides, job.maze, job.start)
    mission = _CACHE.get(key)
    if mission is None:
        mission = _CACHE[key] = load_mission(job.mission, dict(job.overrides), maze=job.maze, start=job.start)
    try:
        result = Run(mission, job.seed, node_stats=job.coverage).run(interrupts=_HONOURED.get())
    except Exception as exc:  # that run fails, the sweep goes on and reports it
        return {
            "seed": job.seed,
            "status": RunStatus.FAILURE,
            "sim_time": 0.0,
            "final_pose": None,
            "reason": f"the run raised {describe(exc)}",
            "code": FailureCode.EXCEPTION,
            "failed_path": None,
            "collisions": 0,
            "first_stop_error": None,
            "wall_time": 0.0,
        }
    stoppers = {name for name, cls in mission.registry.behaviours() if cls.reports == "stop"}
    stops = [
        abs(e["range"] - e["distance"])
        for e in result.events
        if e["kind"] == "behaviour_end"
        and e["name"] in stoppers
        and e["status"] == "SUCCESS"
        and e.get("range") is not None
    ]
    row: SweepRow = {
        "seed": job.seed,
        "status": result.status,
        "sim_time": round(result.sim_time, 6),
        "final_pose": result.final_pose_json,
        "reason": result.reason,
        "code": result.code,
        "failed_path": result.failed_path,
        "collisions": result.collisions,
        "first_stop_error": None if not stops else round(stops[0], 6),
        "wall_time": result.wall_time,
    }
    if job.coverage:
        row["coverage"] = Coverage.of(mission.tree).add(result.node_stats).to_json()
    return row


class Executor(Protocol):
    """What a sweep needs from a pool: results of ``fn`` over ``jobs``, in any order."""

    def imap_unordered(self, fn: Callable[[Job], SweepRow], jobs: Iterable[Job]) -> Iterator[SweepRow]:
        """``fn(job)`` of every job, in any order."""
        ...


class LocalPool:
    """A process pool on this machine (one worker per core by default).

    With ``interrupts`` (see :mod:`thymio_bt.run.interrupts`), a SIGINT/SIGTERM ends the iteration within
    a tenth of a second: the workers (which ignore both signals themselves) are terminated and joined,
    so none is left behind, a run stuck in one with them, and the results already yielded stand. With
    one worker the runs are run in this process: the run at hand ends at its next tick (or, stuck,
    when the grace period of :mod:`~thymio_bt.run.interrupts` is over), code ``INTERRUPTED``."""

    def __init__(self, workers: int | None = None, interrupts: Interrupts | None = None) -> None:
        self.workers = workers or os.cpu_count() or 1
        self.interrupts = interrupts or Interrupts()

    def imap_unordered(self, fn: Callable[[Job], SweepRow], jobs: Iterable[Job]) -> Iterator[SweepRow]:
        """``fn(job)`` of every job, computed by the workers in small chunks, in the order they finish;
        a worker that dies raises :class:`WorkerDied`."""
        jobs = list(jobs)
        if self.workers == 1:
            for job in jobs:
                if self.interrupts.signal:
                    return
                honoured = _HONOURED.set(self.interrupts)  # the run ends at its next tick after a signal
                try:
                    summary = fn(job)
                finally:
                    _HONOURED.reset(honoured)
                yield summary
            return
        size = max(1, min(4, len(jobs) // (self.workers * 8)))  # small: an interrupt loses little
        chunks = [jobs[i : i + size] for i in range(0, len(jobs), size)]
        pool = multiprocessing.Pool(self.workers, initializer=_worker_signals)
        # the pool's processes, to notice one that dies: multiprocessing keeps them private, untyped
        workers = list(pool._pool)  # type: ignore[attr-defined]
        try:
            # chunks by hand: with chunksize > 1, Pool.imap_unordered returns a generator that cannot wait
            # with a timeout, and the loop must look at the interrupts while it waits
            results = pool.imap_unordered(partial(_map_chunk, fn), chunks)
            for _ in chunks:
                while True:
                    if self.interrupts.signal:
                        return
                    try:
                        done = results.next(timeout=0.1)
                        break
                    except multiprocessing.TimeoutError:
                        # a dead worker's chunk never comes back: the pool would wait for ever
                        dead = next((w for w in workers if w.exitcode is not None), None)
                        if dead is not None:
                            raise WorkerDied(dead.exitcode) from None
                yield from done
        finally:
            _end_pool(pool, workers)


class WorkerDied(RuntimeError, ThymioBtError):
    """A sweep worker process ended in the middle of its runs (killed, crashed, or ``os._exit``)."""

    def __init__(self, exitcode: int | None) -> None:
        how = f"killed by {signal.Signals(-exitcode).name}" if exitcode and exitcode < 0 else f"exit code {exitcode}"
        super().__init__(f"a worker process died ({how})")


def _end_pool(pool: Any, workers: list[Any]) -> None:
    """Terminate ``pool`` and join its workers, within :data:`END_WITHIN` s. multiprocessing's own
    terminate drains the task queue under its read lock first, which a worker that died (or one
    blocked reading it) may hold for ever: then the workers are killed instead, and the command ends
    rather than hangs (the stuck terminate is left in a daemon thread; the pool's finalizer is spent)."""
    ender = threading.Thread(target=lambda: (pool.terminate(), pool.join()), daemon=True)
    ender.start()
    ender.join(END_WITHIN)  # realtime: bounding the pool's own clean-up, outside any run
    if ender.is_alive():
        for worker in {*workers, *pool._pool}:
            if worker.exitcode is None:
                worker.kill()
                worker.join(1.0)


#: seconds a sweep's pool has to end before its workers are killed (see :func:`_end_pool`)
END_WITHIN = 5.0


def _map_chunk(fn: Callable[[Job], SweepRow], jobs: list[Job]) -> list[SweepRow]:
    return [fn(job) for job in jobs]


def _worker_signals() -> None:
    """Workers leave Ctrl-C (sent to the whole terminal's process group) and SIGTERM to the parent,
    which stops them itself."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


#: the codes of a run that broke rather than failed: a node's (a plugin's) code or the backend raised.
#: Such a run measures nothing about the mission, so a sweep that has one did not complete (exit 1)
FAULTS = ("EXCEPTION", "BACKEND_ERROR")


@dataclass
class SweepResult:
    """The sweep JSON of DESIGN.md, plus distributions."""

    mission: str
    runs: int
    successes: int
    seed_start: int
    noise: dict[str, float]
    results: list[SweepRow] = field(default_factory=list)
    wall_time: float = 0.0
    #: runs asked for (``runs`` counts those completed: fewer when the sweep was interrupted)
    requested: int = 0
    #: what ended the sweep early: the signal ("SIGINT", "SIGTERM") or a worker's death; None
    interrupted: str | None = None
    #: the ``thymio-bt run`` arguments that reproduce one run, but its ``--seed``
    command: tuple[str, ...] = ()
    #: the tree coverage merged over the runs (:meth:`thymio_bt.run.coverage.Coverage.to_json`), when asked for
    coverage: dict[str, Any] | None = None

    def reproduce(self, seed: int) -> str:
        """The shell command that runs the sweep's run of ``seed`` again, noise settings included."""
        return shlex.join(("thymio-bt", "run", *self.command, "--seed", str(seed)))

    @property
    def faulted(self) -> list[SweepRow]:
        """The runs that broke (code in :data:`FAULTS`): their code raised, unlike a run that failed."""
        return [r for r in self.results if r["code"] in FAULTS]

    @property
    def success_rate(self) -> float:
        """The share of the completed runs that succeeded (0.0 when none completed)."""
        return self.successes / self.runs if self.runs else 0.0

    def distribution(self, key: Literal["sim_time", "first_stop_error"]) -> dict[str, float] | None:
        """min, 5th percentile, median, 95th percentile, max and mean of the results' ``key``; None
        when no result has one."""
        values = sorted(value for r in self.results if (value := r[key]) is not None)
        if not values:
            return None
        q = statistics.quantiles(values, n=20, method="inclusive") if len(values) > 1 else [values[0]] * 19
        return {
            "min": values[0],
            "p5": q[0],
            "median": statistics.median(values),
            "p95": q[-1],
            "max": values[-1],
            "mean": statistics.fmean(values),
        }

    def to_json(self) -> dict[str, Any]:
        """The sweep JSON that ``sweep --out`` writes (a contract, as the run report)."""
        sim_total = sum(r["sim_time"] for r in self.results)
        return {
            "mission": self.mission,
            "runs": self.runs,
            "runs_requested": self.requested,
            "interrupted": self.interrupted,
            "faulted": len(self.faulted),
            "successes": self.successes,
            "success_rate": round(self.success_rate, 6),
            "seed_start": self.seed_start,
            "noise": self.noise,
            "sim_time": self.distribution("sim_time"),
            "first_stop_error": self.distribution("first_stop_error"),
            "failures": {
                code: sum(1 for r in self.results if r["code"] == code)
                for code in sorted({r["code"] for r in self.results if r["code"]})
            },
            "wall_time": round(self.wall_time, 3),
            "aggregate_real_time_factor": round(sim_total / self.wall_time, 1) if self.wall_time else None,
            "results": [
                {k: v for k, v in r.items() if k != "wall_time"}
                | ({} if r["status"] == "SUCCESS" else {"reproduce": self.reproduce(r["seed"])})
                for r in self.results
            ],
            **({} if self.coverage is None else {"coverage": self.coverage}),
        }


def sweep(
    mission: str | Path,
    runs: int,
    seed_start: int = 0,
    overrides: dict[str, str] | None = None,
    maze: str | None = None,
    start: str | None = None,
    executor: Executor | None = None,
    progress: Callable[[SweepRow], None] | None = None,
    interrupts: Interrupts | None = None,
    coverage: bool = False,
) -> SweepResult:
    """Run ``mission`` ``runs`` times with seeds ``seed_start``... and the realistic noise models on
    (``overrides`` such as ``noise.wheel=0`` change them). A signal noted in ``interrupts`` ends it
    early with the runs completed so far. With ``coverage``, the result has the tree coverage of the
    runs, merged as they come in."""
    import time

    from thymio_bt.mission import load_mission
    from thymio_bt.run.coverage import Coverage

    interrupts = interrupts or Interrupts()
    settings = REALISTIC.settings()
    settings.update(overrides or {})
    spec = load_mission(mission, settings, maze=maze, start=start)  # fail fast, in this process
    overrides_key = tuple(sorted(settings.items()))
    key = content_key(spec.sources, overrides_key, maze, start)
    jobs = [
        Job(str(mission), seed, overrides_key, maze, start, key, coverage)
        for seed in range(seed_start, seed_start + runs)
    ]
    merged = Coverage.of(spec.tree) if coverage else None
    executor = executor or LocalPool(interrupts=interrupts)
    results = []
    began = time.perf_counter()
    stopped = None
    try:
        for summary in executor.imap_unordered(run_job, jobs):
            ran = summary.pop("coverage", None)
            if merged is not None and ran is not None:
                merged.merge(ran)
            results.append(summary)
            if progress is not None:
                progress(summary)
            if interrupts.signal:
                break
    except WorkerDied as exc:
        stopped = str(exc)
    except Interrupted:
        pass  # broken into while it waited for a result (an executor that cannot wait briefly): they stand
    results.sort(key=lambda r: r["seed"])
    command = (
        str(mission),
        *(a for k, v in sorted(settings.items()) for a in ("--set", f"{k}={v}")),
        *(("--maze", maze) if maze else ()),
        *(("--start", start) if start else ()),
    )
    return SweepResult(
        mission=spec.name,
        runs=len(results),
        successes=sum(r["status"] == "SUCCESS" for r in results),
        seed_start=seed_start,
        noise=spec.noise.model_dump(),
        results=results,
        wall_time=time.perf_counter() - began,
        requested=runs,
        interrupted=interrupts.name or stopped,
        command=command,
        coverage=None if merged is None else merged.to_json(),
    )


__all__ = ["FAULTS", "Executor", "Job", "LocalPool", "SweepResult", "run_job", "sweep"]
