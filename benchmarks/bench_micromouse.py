"""Micromouse: explore, return and fast-run generated 16 x 16 contest mazes, with noise on.

Issue "Beyond the course": on 30 generated mazes of the contest kind (centre goal, loops, dead
ends) and the 4 x 4 example, with every robot profile and the realistic noise models, the goal is
reached in every run, no run touches a wall, the fast run is never longer than the exploration,
and a full 16 x 16 run costs <= 2 s of wall time. Prints one table, saves the numbers in
results.json. Run: ``python benchmarks/bench_micromouse.py [--mazes 30] [--robots course,enki,real]``.
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import tempfile
from pathlib import Path
from typing import Any

from _common import ROOT, machine, save_results, table

from thymio_bt.maze.generate import contest_maze
from thymio_bt.maze.micromouse import to_text
from thymio_bt.mission import load_mission
from thymio_bt.robot.noise import REALISTIC
from thymio_bt.run.runner import run_mission

MISSION = ROOT / "missions" / "micromouse.yaml"


def one(job: tuple[str, str, int]) -> dict[str, Any]:
    maze, robot, seed = job
    settings = {f"noise.{k}": str(v) for k, v in REALISTIC.model_dump().items()}
    settings["robot"] = robot
    result = run_mission(load_mission(MISSION, settings, maze=maze), seed=seed)
    phases = {p.name: p.as_dict() for p in result.phases}
    return {
        "maze": Path(maze).name,
        "robot": robot,
        "seed": seed,
        "status": result.status,
        "code": result.code,
        "collisions": result.collisions,
        "goal": bool(result.goal and result.goal.reached),
        "search": phases.get("search", {}).get("duration"),
        "cells": phases.get("search", {}).get("cells"),
        "fast": phases.get("fast run", {}).get("duration"),
        "sim_time": result.sim_time,
        "wall_time": result.wall_time,
        "min_clearance": result.min_clearance,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mazes", type=int, default=30)
    parser.add_argument("--first", type=int, default=0, help="the first generated maze's seed")
    parser.add_argument("--loops", type=float, default=0.1, help="the fraction of inner walls removed")
    parser.add_argument("--robots", default="course,enki,real")
    args = parser.parse_args()
    robots = args.robots.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        mazes = [str(ROOT / "mazes" / "micromouse_4x4.txt")]
        for seed in range(args.first, args.first + args.mazes):
            path = Path(tmp) / f"contest_{seed:02d}.txt"
            path.write_text(to_text(contest_maze(seed, loops=args.loops)))
            mazes.append(str(path))
        jobs = [(maze, robot, n) for robot in robots for n, maze in enumerate(mazes)]
        with multiprocessing.Pool() as pool:
            runs = pool.map(one, jobs, chunksize=1)
    rows = []
    for robot in robots:
        mine = [r for r in runs if r["robot"] == robot]
        big = [r for r in mine if r["maze"] != "micromouse_4x4.txt"]
        ok = [r for r in mine if r["status"] == "SUCCESS"]
        rows.append(
            (
                robot,
                f"{len(ok)}/{len(mine)}",
                f"{sum(r['goal'] for r in mine)}/{len(mine)}",
                sum(1 for r in mine if r["collisions"]),
                sum(1 for r in ok if r["fast"] is not None and r["fast"] > r["search"]),
                f"{statistics.median(r['search'] for r in ok):.0f}" if ok else "-",
                f"{statistics.median(r['fast'] for r in ok):.0f}" if ok else "-",
                f"{statistics.median(r['cells'] for r in ok):.0f}" if ok else "-",
                f"{statistics.median(r['wall_time'] for r in big):.2f} / {max(r['wall_time'] for r in big):.2f}",
                ", ".join(f"{r['maze']}:{r['code']}" for r in mine if r["status"] != "SUCCESS") or "-",
            )
        )
    print(
        f"{len(mazes)} mazes (the 4 x 4 example and {args.mazes} generated 16 x 16 from seed {args.first}, "
        f"loops {args.loops:g}), realistic noise, seed = maze index"
    )
    print(
        table(
            rows,
            (
                "robot",
                "success",
                "goal",
                "collided",
                "fast > search",
                "search s (median)",
                "fast s (median)",
                "cells seen",
                "wall s 16x16 (median / max)",
                "failures",
            ),
        )
    )
    save_results(
        "micromouse",
        {"machine": machine(), "mazes": args.mazes, "first": args.first, "loops": args.loops, "runs": runs},
    )


if __name__ == "__main__":
    main()
