"""Helpers shared by the benchmark scripts (timing, machine facts, result file, tables).

Not a benchmark itself and not a test: the leading underscore keeps it out of pytest's
collection, and the scripts import it as a sibling module (``python benchmarks/bench_*.py``
puts ``benchmarks/`` on ``sys.path``).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results.json"


def median_time(fn: Callable[[], Any], repeats: int = 5) -> tuple[float, list[float], Any]:
    """Run ``fn`` ``repeats`` times; (median seconds, all samples, last return value)."""
    samples, value = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        value = fn()
        samples.append(time.perf_counter() - t0)
    return statistics.median(samples), samples, value


def per_call_us(loop: Callable[[int], Any], n: int, repeats: int = 5) -> tuple[float, list[float]]:
    """Median µs per iteration of ``loop(n)`` (which runs n iterations), over ``repeats`` timings."""
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        loop(n)
        samples.append((time.perf_counter() - t0) / n * 1e6)
    return statistics.median(samples), samples


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def machine() -> dict[str, Any]:
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    return {
        "nproc": os.cpu_count(),
        "cpu_model": cpu_model(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "loadavg_at_start": [round(x, 2) for x in load] if load else None,
        "packages": {
            d: version(d)
            for d in (
                "thymio-bt",
                "pymunk",
                "py_trees",
                "pydantic",
                "numpy",
                "PyYAML",
                "click",
                "ir-sim",
                "shapely",
                "matplotlib",
            )
        },
    }


def save_results(section: str, data: dict[str, Any]) -> None:
    """Merge ``data`` under ``section`` into benchmarks/results.json (other sections are kept)."""
    try:
        doc = json.loads(RESULTS.read_text())
    except (OSError, ValueError):
        doc = {}
    doc["date"] = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    doc["machine"] = machine()
    doc.setdefault("results", {})[section] = {"date": doc["date"], **data}
    RESULTS.write_text(json.dumps(doc, indent=1) + "\n")


def table(rows: list[tuple[str, ...]], header: tuple[str, ...]) -> str:
    """A plain-text table with columns padded to width."""
    cols = list(zip(header, *rows, strict=True))
    widths = [max(len(str(c)) for c in col) for col in cols]

    def line(r: tuple[str, ...]) -> str:
        return "  ".join(
            str(c).ljust(w) if i == 0 else str(c).rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True))
        )

    sep = "  ".join("-" * w for w in widths)
    return "\n".join([line(header), sep, *(line(r) for r in rows)])


def verdict(value: float, target: float, higher_is_better: bool = True) -> str:
    ok = value >= target if higher_is_better else value <= target
    return "MET" if ok else "MISSED"
