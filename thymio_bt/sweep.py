"""Run a mission many times with consecutive seeds and the noise models on, in parallel.

The executor boundary is one picklable function, :func:`run_job`, mapped over :class:`Job` s by
anything with ``imap_unordered(fn, iterable)``: the local process pool here, and the same call on
``ray.util.multiprocessing.Pool`` (Ray) or a small adapter over ``dask.distributed.Client.map``
(Dask) to go past one machine. Results are sorted by seed, so the same sweep gives the same table.

Example::

    result = sweep("missions/maze_bonus.yaml", runs=100)
    result.success_rate        # 1.0
"""

from __future__ import annotations

import os
import statistics
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Protocol

from .sim.noise import REALISTIC


@dataclass(frozen=True)
class Job:
    """One run of a sweep: everything a worker needs, picklable."""

    mission: str
    seed: int
    overrides: tuple[tuple[str, str], ...] = ()
    maze: str | None = None
    start: str | None = None


_CACHE: dict[tuple[Any, ...], Any] = {}


def run_job(job: Job) -> dict[str, Any]:
    """Run one job and summarise it (the function executors map); missions are loaded once per worker."""
    from .mission import load_mission
    from .runner import Run

    key = (job.mission, job.overrides, job.maze, job.start)
    mission = _CACHE.get(key)
    if mission is None:
        mission = _CACHE[key] = load_mission(job.mission, dict(job.overrides), maze=job.maze, start=job.start)
    result = Run(mission, job.seed).run()
    stops = [abs(e["range"] - e["distance"]) for e in result.events
             if e["kind"] == "behaviour_end" and e["name"] == "MoveUntilWall" and e["status"] == "SUCCESS"
             and e.get("range") is not None]
    return {"seed": job.seed, "status": result.status, "sim_time": round(result.sim_time, 6),
            "final_pose": result.final_pose, "reason": result.reason, "code": result.code,
            "failed_path": result.failed_path, "collisions": result.collisions,
            "first_stop_error": None if not stops else round(stops[0], 6), "wall_time": result.wall_time}


class Executor(Protocol):
    """What a sweep needs from a pool: results of ``fn`` over ``jobs``, in any order."""

    def imap_unordered(self, fn: Callable[[Job], dict[str, Any]], jobs: Iterable[Job]) -> Iterator[dict[str, Any]]: ...


class LocalPool:
    """A process pool on this machine (one worker per core by default)."""

    def __init__(self, workers: int | None = None) -> None:
        self.workers = workers or os.cpu_count() or 1

    def imap_unordered(self, fn: Callable[[Job], dict[str, Any]], jobs: Iterable[Job]) -> Iterator[dict[str, Any]]:
        jobs = list(jobs)
        if self.workers == 1:
            yield from map(fn, jobs)
            return
        chunk = max(1, len(jobs) // (self.workers * 8))
        with ProcessPoolExecutor(self.workers) as pool:
            yield from pool.map(fn, jobs, chunksize=chunk)


@dataclass
class SweepResult:
    """The sweep JSON of DESIGN.md, plus distributions."""

    mission: str
    runs: int
    successes: int
    seed_start: int
    noise: dict[str, float]
    results: list[dict[str, Any]] = field(default_factory=list)
    wall_time: float = 0.0

    @property
    def success_rate(self) -> float:
        return self.successes / self.runs if self.runs else 0.0

    def distribution(self, key: str) -> dict[str, float] | None:
        values = sorted(r[key] for r in self.results if r.get(key) is not None)
        if not values:
            return None
        q = statistics.quantiles(values, n=20, method="inclusive") if len(values) > 1 else [values[0]] * 19
        return {"min": values[0], "p5": q[0], "median": statistics.median(values), "p95": q[-1],
                "max": values[-1], "mean": statistics.fmean(values)}

    def to_json(self) -> dict[str, Any]:
        sim_total = sum(r["sim_time"] for r in self.results)
        return {
            "mission": self.mission, "runs": self.runs, "successes": self.successes,
            "success_rate": round(self.success_rate, 6), "seed_start": self.seed_start, "noise": self.noise,
            "sim_time": self.distribution("sim_time"), "first_stop_error": self.distribution("first_stop_error"),
            "failures": {code: sum(1 for r in self.results if r["code"] == code)
                         for code in sorted({r["code"] for r in self.results if r["code"]})},
            "wall_time": round(self.wall_time, 3),
            "aggregate_real_time_factor": round(sim_total / self.wall_time, 1) if self.wall_time else None,
            "results": [{k: v for k, v in r.items() if k != "wall_time"} for r in self.results],
        }


def sweep(mission: str | Path, runs: int, seed_start: int = 0, overrides: dict[str, str] | None = None,
          maze: str | None = None, start: str | None = None, executor: Executor | None = None,
          progress: Callable[[dict[str, Any]], None] | None = None) -> SweepResult:
    """Run ``mission`` ``runs`` times with seeds ``seed_start``... and the realistic noise models on
    (``overrides`` such as ``noise.wheel=0`` change them)."""
    import time

    from .mission import load_mission

    settings = {f"noise.{k}": str(v) for k, v in REALISTIC.model_dump().items()}
    settings.update(overrides or {})
    spec = load_mission(mission, settings, maze=maze, start=start)     # fail fast, in this process
    jobs = [Job(str(mission), seed, tuple(sorted(settings.items())), maze, start)
            for seed in range(seed_start, seed_start + runs)]
    executor = executor or LocalPool()
    results = []
    began = time.perf_counter()
    for summary in executor.imap_unordered(run_job, jobs):
        results.append(summary)
        if progress is not None:
            progress(summary)
    results.sort(key=lambda r: r["seed"])
    return SweepResult(mission=spec.name, runs=runs, successes=sum(r["status"] == "SUCCESS" for r in results),
                       seed_start=seed_start, noise=spec.noise.model_dump(), results=results,
                       wall_time=time.perf_counter() - began)


__all__ = ["Executor", "Job", "LocalPool", "SweepResult", "run_job", "sweep"]
