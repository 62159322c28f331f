"""Picture benchmark: ``--gif`` of ``missions/maze_bonus.yaml`` (79 s simulated, 200 frames at the
default speed-up 4), and ``--plot`` and ``--plot-signals`` of the same run.

Each measurement runs in a fresh process (``python -c``, matplotlib imported before the clock
starts), on this checkout and, with ``--against REV``, on that git revision (extracted with
``git archive`` into a temporary folder), alternately, REPEATS times: the median wall time and the
median CPU time of the process (``time.process_time``: what the drawing itself costs, whatever else
the machine runs), the GIF's size in pixels, its frames and its bytes. Target (issue 46): the GIF
at least 5x faster than before, and larger.

Results go to benchmarks/results.json (section "pictures").
Usage (from the repo root): python benchmarks/bench_pictures.py [--repeats 3] [--against REV]
"""

from __future__ import annotations

import argparse
import io
import json
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

from _common import ROOT, save_results, table

MISSION = "maze_bonus"

#: run in the child process: record the run, then time each picture (wall and CPU seconds)
CHILD = """
import json, sys, tempfile, time
from pathlib import Path
import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot
from PIL import Image
from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.viz import plots
try:
    from thymio_bt.viz.animation import animate
except ImportError:  # before issue 46 the animation was plots.animate
    animate = plots.animate
recorder = Recorder()
recording = recorder.finish(Run(load_mission(sys.argv[1])).run(on_tick=recorder))
out, folder = {}, Path(tempfile.mkdtemp())
pictures = (("gif", lambda p: animate(recording, p, speedup=4)), ("plot", lambda p: plots.plot_run(recording, p)),
            ("signals", lambda p: plots.plot_signals(recording, p)))
for name, draw in pictures:
    path = folder / ("run.gif" if name == "gif" else f"{name}.png")
    wall, cpu = time.perf_counter(), time.process_time()
    draw(path)
    out[name] = {"wall_s": time.perf_counter() - wall, "cpu_s": time.process_time() - cpu, "bytes": path.stat().st_size}
    image = Image.open(path)
    out[name]["size"] = list(image.size)
    out[name]["frames"] = getattr(image, "n_frames", 1)
print(json.dumps(out))
"""


def measure(checkout: Path) -> dict:
    """One child process on ``checkout``: its pictures' times and sizes."""
    done = subprocess.run(
        [sys.executable, "-c", CHILD, MISSION],
        cwd=checkout,
        env={"PYTHONPATH": str(checkout), "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg"},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.splitlines()[-1])


def extract(rev: str, folder: Path) -> Path:
    """The package as it was at ``rev``, in ``folder``."""
    archive = subprocess.run(
        ["git", "archive", rev, "thymio_bt", "missions", "mazes", "schema", "assignments"],
        cwd=ROOT,
        capture_output=True,
        check=True,
    ).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(folder, filter="data")
    return folder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--against", metavar="REV", help="also measure this git revision, alternately")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        checkouts = {"this checkout": ROOT}
        if args.against:
            checkouts[args.against] = extract(args.against, Path(tmp))
        samples: dict[str, list[dict]] = {name: [] for name in checkouts}
        for _ in range(args.repeats):
            for name, folder in checkouts.items():
                samples[name].append(measure(folder))
    results, rows = {}, []
    for name, runs in samples.items():
        results[name] = {}
        for picture in ("gif", "plot", "signals"):
            wall = statistics.median(r[picture]["wall_s"] for r in runs)
            cpu = statistics.median(r[picture]["cpu_s"] for r in runs)
            last = runs[-1][picture]
            results[name][picture] = {
                "wall_s": round(wall, 3),
                "cpu_s": round(cpu, 3),
                **{k: last[k] for k in ("size", "frames", "bytes")},
            }
            size = "x".join(map(str, last["size"]))
            rows.append(
                (name, picture, f"{wall:.2f}", f"{cpu:.2f}", size, str(last["frames"]), f"{last['bytes'] // 1024}")
            )
    print(table(rows, ("checkout", "picture", "wall s", "cpu s", "pixels", "frames", "KiB")))
    if args.against:
        before, after = results[args.against]["gif"], results["this checkout"]["gif"]
        wall, cpu = before["wall_s"] / after["wall_s"], before["cpu_s"] / after["cpu_s"]
        print(f"--gif: {wall:.1f}x faster (wall), {cpu:.1f}x (cpu) than {args.against}")
    save_results("pictures", {"mission": MISSION, "repeats": args.repeats, **results})


if __name__ == "__main__":
    main()
