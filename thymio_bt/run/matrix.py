"""A robustness matrix: the same sweep in every combination of settings (robots, sensor models, ...).

``thymio-bt sweep MISSION --matrix robot=course,enki,real --matrix sensor_model=rays,cone`` runs
the sweep once per cell of the cartesian product and tabulates, per cell, the success rate, how far
the robot ended from where the mission ends on the course's ideal robot (its noise-free run: the
"right pocket"), and how many runs touched a wall.

Example (one run per cell here; ``thymio-bt sweep`` runs them in parallel):

>>> from thymio_bt.run.sweep import LocalPool
>>> cells = run_matrix("square", 1, {"robot": ["course", "enki"]}, executor=LocalPool(workers=1))
>>> [(c.settings["robot"], c.row()["success_rate"], c.row()["final_error_median"]) for c in cells]  # error in m
[('course', 1.0, 0.001238), ('enki', 1.0, 0.001593)]
>>> parse_axes(["robot=course,enki", "sensor_model=rays"])
{'robot': ['course', 'enki'], 'sensor_model': ['rays']}
"""

from __future__ import annotations

import itertools
import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from thymio_bt.errors import UserError
from thymio_bt.run.sweep import SweepResult, SweepRow, sweep

if TYPE_CHECKING:
    from thymio_bt.geometry import Pose


@dataclass
class Cell:
    """One combination of the matrix's settings and its sweep."""

    settings: dict[str, str]
    result: SweepResult
    #: the final pose of the mission's noise-free run on the course's robot, or None (no robot at the end)
    reference: Pose | None

    def errors(self) -> list[float]:
        """Each run's distance from the reference final pose (m); inf when it ended without a robot."""
        if self.reference is None:
            return []
        return [
            math.inf
            if r["final_pose"] is None
            else math.hypot(r["final_pose"]["x"] - self.reference.x, r["final_pose"]["y"] - self.reference.y)
            for r in self.result.results
        ]

    def row(self) -> dict[str, Any]:
        """The cell's line of the matrix table: success rate, collisions, distance from the reference end."""
        errors = sorted(self.errors())
        finite = [e for e in errors if math.isfinite(e)]
        return {
            "settings": self.settings,
            "runs": self.result.runs,
            "success_rate": round(self.result.success_rate, 6),
            "runs_with_collision": sum(1 for r in self.result.results if r["collisions"]),
            "final_error_median": round(statistics.median(finite), 6) if finite else None,
            "final_error_max": round(errors[-1], 6) if errors and math.isfinite(errors[-1]) else None,
            "failures": self.result.to_json()["failures"],
        }


def parse_axes(specs: tuple[str, ...] | list[str]) -> dict[str, list[str]]:
    """``["robot=course,enki"]`` → ``{"robot": ["course", "enki"]}``, with a clear error for bad input."""
    axes: dict[str, list[str]] = {}
    for spec in specs:
        name, sep, values = spec.partition("=")
        choices = [v.strip() for v in values.split(",") if v.strip()]
        if not sep or not name.strip() or not choices:
            raise UserError(
                f"--matrix expects NAME=VALUE,VALUE..., got '{spec}' (hint: --matrix robot=course,enki,real)"
            )
        if name.strip() in axes:
            raise UserError(f"--matrix {name.strip()} is given twice (hint: list all its values in one --matrix)")
        axes[name.strip()] = choices
    return axes


def run_matrix(
    mission: str | Path,
    runs: int,
    axes: dict[str, list[str]],
    seed_start: int = 0,
    overrides: dict[str, str] | None = None,
    maze: str | None = None,
    start: str | None = None,
    executor: Any = None,
    progress: Callable[[SweepRow], None] | None = None,
    interrupts: Any = None,
) -> list[Cell]:
    """The sweep of ``mission`` in every combination of ``axes`` (a ``--set`` name → its values)."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    base = dict(overrides or {})
    quiet = {**base, "noise.wheel": "0", "noise.odometry": "0", "noise.range_sd": "0", "robot": "course"}
    quiet.pop("sensor_model", None)
    reference = Run(load_mission(mission, quiet, maze=maze, start=start)).run().final_pose
    cells = []
    names = list(axes)
    for values in itertools.product(*(axes[n] for n in names)):
        settings = dict(zip(names, values, strict=True))  # one value per axis
        result = sweep(
            mission,
            runs,
            seed_start,
            {**base, **settings},
            maze,
            start,
            executor=executor,
            progress=progress,
            interrupts=interrupts,
        )
        cells.append(Cell(settings, result, reference))
        if result.interrupted:
            break
    return cells
