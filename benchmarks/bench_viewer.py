"""The run's page (``view``, ``run --html``): its size and how fast it is written and opened.

Issue 43's targets: a micromouse 16 x 16 run (about 7000 ticks) gives a page of at most 5 MB that
opens in Chromium in at most 2 s; the page of a course run is written in less than a second. Runs
``missions/micromouse.yaml`` on generated 16 x 16 contest mazes and the course missions, writes each
page (median of 5), and opens it in headless Chromium (driven as tests/test_grade_site.py does):
the open time is from navigation start to the first frame after the load event (the page's script
has drawn the maze, tree and timeline by then), median of 3 fresh tabs. Prints one table, saves the
numbers in results.json. Run: ``python benchmarks/bench_viewer.py [--mazes 3]``.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

from _common import ROOT, median_time, save_results, table, verdict

from thymio_bt.logs.recording import Recorder, Recording
from thymio_bt.maze.generate import contest_maze
from thymio_bt.maze.micromouse import to_text
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.viz.page import write_page

sys.path.insert(0, str(ROOT / "tests"))
from test_grade_site import BROWSERS, Chromium  # noqa: E402  # the tests' browser driver

FIRST_FRAME = "new Promise(done => requestAnimationFrame(() => done(performance.now())))"


def record(mission: str, maze: str | None = None) -> Recording:
    recorder = Recorder(statuses=True)
    return recorder.finish(Run(load_mission(mission, maze=maze)).run(on_tick=recorder))


def open_ms(browser: Chromium, page: Path) -> float:
    """Milliseconds from navigation start to the first frame after the load event, median of 3."""
    times = []
    for _ in range(3):
        tab = browser.open(page.as_uri())
        problems = tab.problems()
        assert problems == [], problems
        answer = browser.call(
            "Runtime.evaluate", {"expression": FIRST_FRAME, "awaitPromise": True, "returnByValue": True}, tab.session
        )
        times.append(answer["result"]["value"])
        tab.close()
    return statistics.median(times)


def measure(browser: Chromium, name: str, recording: Recording, folder: Path) -> dict[str, Any]:
    page = folder / f"{name}.html"
    write, _, _ = median_time(lambda: write_page([recording], page))
    return {
        "run": name,
        "ticks": len(recording.samples),
        "nodes": len(recording.header["tree"]),
        "bytes": page.stat().st_size,
        "write_s": write,
        "open_ms": open_ms(browser, page),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mazes", type=int, default=3, help="generated 16 x 16 mazes (seeds 0..N-1)")
    args = parser.parse_args()
    exe = next((path for name in BROWSERS if (path := shutil.which(name))), None)
    if exe is None:
        raise SystemExit("needs Chromium")
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        browser = Chromium(exe, folder)
        try:
            browser.call("Browser.getVersion")
            for mission in ("maze_part1_2", "course_full"):
                rows.append(measure(browser, mission, record(mission), folder))
            for seed in range(args.mazes):
                maze = folder / f"contest_{seed:02d}.txt"
                maze.write_text(to_text(contest_maze(seed, loops=0.1)))
                rows.append(measure(browser, f"micromouse 16x16 #{seed}", record("micromouse", str(maze)), folder))
        finally:
            browser.close()
    mouse = [r for r in rows if r["run"].startswith("micromouse")]
    course = [r for r in rows if not r["run"].startswith("micromouse")]
    print(
        table(
            [
                (
                    r["run"],
                    str(r["ticks"]),
                    str(r["nodes"]),
                    f"{r['bytes'] / 1e6:.2f}",
                    f"{r['write_s'] * 1000:.0f}",
                    f"{r['open_ms']:.0f}",
                )
                for r in rows
            ],
            ("run", "ticks", "nodes", "page MB", "write ms", "open ms"),
        )
    )
    biggest = max(mouse, key=lambda r: r["bytes"])
    checks = {
        "micromouse page <= 5 MB": verdict(biggest["bytes"], 5e6, higher_is_better=False),
        "micromouse opens <= 2 s": verdict(max(r["open_ms"] for r in mouse), 2000, higher_is_better=False),
        "course page written < 1 s": verdict(max(r["write_s"] for r in course), 1.0, higher_is_better=False),
    }
    for what, result in checks.items():
        print(f"{what}: {result}")
    save_results("viewer", {"runs": rows, "targets": checks})


if __name__ == "__main__":
    main()
