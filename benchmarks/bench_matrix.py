"""Robustness matrix: every mission x robot profile (course, enki, real), noisy runs per cell.

Issue "Missions that survive a real Thymio's sensors": the target is >= 99 % success with the
mission's expectations holding and no collision, in every cell. Prints one table (the README's),
saves the numbers in results.json. Run: ``python benchmarks/bench_matrix.py [--runs 100]``.
"""

from __future__ import annotations

import argparse

from _common import ROOT, machine, save_results, table

from thymio_bt.run.matrix import run_matrix

MISSIONS = (
    "maze_part1_2",
    "maze_bonus",
    "maze_6x6_left",
    "maze_6x6_right",
    "course_full",
    "square",
    "waypoints",
    "waypoints_obstacles",
)
ROBOTS = ["course", "enki", "real"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    args = parser.parse_args()
    rows, data = [], {}
    for name in MISSIONS:
        cells = run_matrix(ROOT / "missions" / f"{name}.yaml", args.runs, {"robot": ROBOTS})
        data[name] = [cell.row() for cell in cells]
        rows.append(
            (
                name,
                *(f"{100 * c.result.success_rate:.0f} % / {c.row()['runs_with_collision']}" for c in cells),
                "; ".join(
                    f"{c.settings['robot']}: " + ", ".join(f"{k} {v}" for k, v in c.row()["failures"].items())
                    for c in cells
                    if c.row()["failures"]
                ),
            )
        )
    print(f"{args.runs} noisy runs per cell (seeds 0..{args.runs - 1}); success % / runs that touched a wall")
    print(table(rows, ("mission", *ROBOTS, "failures")))
    save_results("matrix", {"runs": args.runs, "machine": machine(), "cells": data})


if __name__ == "__main__":
    main()
