"""Instructions per mission run, counted by callgrind: a figure a noisy machine cannot move.

For each checkout compared (this one, and ``--against REV`` built in a temporary git worktree), one
Python process under ``valgrind --tool=callgrind`` loads MISSION and runs it once, and another runs it
``1 + K`` times; the difference divided by K is what one ``run()`` costs, start-up and imports
cancelled out. The checkouts are measured alternately, ``--rounds`` times, so that a change on the
machine touches both alike (the counts should not move at all; a difference between rounds is
reported). Also prints the whole-process count of ``thymio-bt run MISSION --quiet``.

With ``--irsim``, IR-SIM 2.12's run of the same maze and simulated time (``bench_run.py``'s fastest
variant, rectangles with ``stop``) is counted the same way: its steps alone (each mission's
``irsim.make`` counted apart and taken off, as its wall time leaves the build out), for the instruction
ratio beside the wall-time one.

    python benchmarks/bench_instructions.py                       # this checkout
    python benchmarks/bench_instructions.py --against HEAD~5      # before/after, alternated
    python benchmarks/bench_instructions.py --irsim               # and IR-SIM's run (a few minutes)

Needs valgrind (``apt-get install valgrind``); each count takes 10-30 s.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from _common import ROOT, save_results, table

MISSION = "missions/maze_part1_2.yaml"
RUNS = """
import sys
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
mission = load_mission(sys.argv[1])
for _ in range(int(sys.argv[2])):
    result = Run(mission).run()
print(result.status, result.ticks)
"""
#: argv: benchmarks folder, IR-SIM variant, simulated seconds, builds, missions
IRSIM_RUNS = """
import sys, tempfile
from pathlib import Path
sys.path.insert(0, sys.argv[1])
import bench_run
from thymio_bt.maze import load_maze
shape, mode = bench_run.VARIANTS[sys.argv[2]]
sim_time, builds, missions = float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
maze = load_maze(bench_run.MAZE)
irsim = bench_run.import_irsim()
with tempfile.TemporaryDirectory() as tmp:
    world = Path(tmp) / "world.yaml"
    bench_run.irsim_world(world, shape, mode, maze.spawn("part1"))
    for _ in range(builds):
        irsim.make(str(world), headless=True, log_level="ERROR").end(ending_time=0)
    for _ in range(missions):
        bench_run.irsim_mission(irsim, world, sim_time, maze.spawn("part2"))
"""
IRSIM_VARIANT = "rectangles, stop"


def instructions(cmd: list[str], cwd: Path) -> int:
    """Instructions (callgrind's Ir) of a whole process, children not followed."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        # string hashing is randomised per process, which moves a count by up to half a million
        env = {**os.environ, "PYTHONHASHSEED": "0"}
        # once without valgrind first: a process that compiles sources whose .pyc files are missing
        # or stale would count the compiler too (tens of millions of instructions); it must be free
        # to write them (a shell that sets PYTHONDONTWRITEBYTECODE had counted 330 M of compiling)
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        subprocess.run(cmd, cwd=cwd, capture_output=True, env=env)
        done = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *cmd],
            cwd=cwd,
            capture_output=True,
            text=True,
            env=env,
        )
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} failed under callgrind:\n{done.stderr[-2000:]}")
        match = re.search(r"Collected : (\d+)", done.stderr) or re.search(r"summary: (\d+)", out.read_text())
        return int(match.group(1))


def measure(checkout: Path, python: str, extra_runs: int) -> dict[str, float]:
    """Instructions of one run() in-process (by difference) and of the whole CLI process."""
    script = [python, "-c", RUNS, MISSION]
    one = instructions([*script, "1"], checkout)
    more = instructions([*script, str(1 + extra_runs)], checkout)
    cli = instructions([python, "-m", "thymio_bt.cli", "run", MISSION, "--quiet"], checkout)
    return {"run_Ir": (more - one) / extra_runs, "process_Ir": cli, "setup_Ir": one - (more - one) / extra_runs}


def measure_irsim(python: str, extra_runs: int) -> dict[str, float]:
    """Instructions of IR-SIM's run of MISSION's maze for MISSION's simulated time: a mission (build
    and steps) and a build, each by difference; the steps are the one less the other."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    sim_time = Run(load_mission(ROOT / MISSION)).run().sim_time
    script = [python, "-c", IRSIM_RUNS, str(Path(__file__).resolve().parent), IRSIM_VARIANT, str(sim_time)]
    base = instructions([*script, "0", "1"], ROOT)
    missions = instructions([*script, "0", str(1 + extra_runs)], ROOT)
    builds = instructions([*script, str(extra_runs), "1"], ROOT)
    mission_ir, build_ir = (missions - base) / extra_runs, (builds - base) / extra_runs
    return {
        "variant": IRSIM_VARIANT,
        "sim_time": sim_time,
        "mission_Ir": mission_ir,
        "build_Ir": build_ir,
        "run_Ir": mission_ir - build_ir,
    }


def worktree(rev: str, into: Path) -> Path:
    subprocess.run(["git", "worktree", "add", "--detach", str(into), rev], cwd=ROOT, check=True, capture_output=True)
    return into


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--against", metavar="REV", help="also count this git revision, alternately")
    parser.add_argument("--rounds", type=int, default=2, help="alternations (default 2)")
    parser.add_argument("--extra-runs", type=int, default=2, help="K extra runs for the difference")
    parser.add_argument("--irsim", action="store_true", help="also count IR-SIM's run (pip install -e .[bench])")
    args = parser.parse_args(argv)
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not installed (hint: apt-get install valgrind)")
    checkouts = {"this checkout": ROOT}
    tmp = Path(tempfile.mkdtemp(prefix="bench-instr-"))
    try:
        if args.against:
            checkouts[args.against] = worktree(args.against, tmp / "against")
        samples: dict[str, list[dict[str, float]]] = {name: [] for name in checkouts}
        for round_ in range(args.rounds):
            for name, path in checkouts.items():
                # python -c and -m put the working folder first on sys.path: each checkout's own sources
                samples[name].append(measure(path, sys.executable, args.extra_runs))
                print(f"round {round_ + 1}: {name}: {samples[name][-1]['run_Ir'] / 1e6:.1f} M per run", file=sys.stderr)
    finally:
        if args.against:
            subprocess.run(
                ["git", "worktree", "remove", "--force", str(tmp / "against")], cwd=ROOT, capture_output=True
            )
        shutil.rmtree(tmp, ignore_errors=True)
    rows, out = [], {}
    for name, runs in samples.items():
        run_ir = [r["run_Ir"] for r in runs]
        spread = max(run_ir) - min(run_ir)
        out[name] = {
            "run_Ir": run_ir[0],
            "process_Ir": runs[0]["process_Ir"],
            "setup_Ir": runs[0]["setup_Ir"],
            "spread_Ir": spread,
        }
        rows.append(
            (
                name,
                f"{run_ir[0] / 1e6:.1f} M",
                f"{runs[0]['setup_Ir'] / 1e6:.0f} M",
                f"{runs[0]['process_Ir'] / 1e6:.0f} M",
                f"{spread / 1e6:.2f} M",
            )
        )
    print(f"{MISSION}: instructions (callgrind Ir)")
    print(table(rows, ("checkout", "one run()", "imports+load", "whole CLI process", "spread over rounds")))
    if args.against:
        base, new = out[args.against]["run_Ir"], out["this checkout"]["run_Ir"]
        print(f"run(): {base / new:.2f}x fewer instructions than {args.against}")
    if args.irsim:
        irsim = out["irsim"] = measure_irsim(sys.executable, args.extra_runs)
        irsim["ratio_over_thymio_bt"] = irsim["run_Ir"] / out["this checkout"]["run_Ir"]
        print(
            f"IR-SIM 2.12 ({irsim['variant']}), the same walls for {irsim['sim_time']:.1f} s: "
            f"{irsim['run_Ir'] / 1e6:.0f} M for its steps (+ {irsim['build_Ir'] / 1e6:.0f} M to build the world): "
            f"{irsim['ratio_over_thymio_bt']:.1f}x this checkout's run()"
        )
    save_results("instructions", out)
    return out


if __name__ == "__main__":
    main()
