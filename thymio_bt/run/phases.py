"""A run's phases: each use of a mission subtree (``subtrees:``), when it ran and what it saw.

A mission such as ``micromouse.yaml`` is written as phases (search, return, fast run); its report
says how long each took, from the behaviours' events, so nobody has to read them to find out.

Example:

>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import run_mission
>>> result = run_mission(load_mission("micromouse"))
>>> [(p.name, p.duration, p.cells) for p in result.phases]
[('search', 45.2, 11), ('return', 70.2, 14), ('fast run', 36.5, 9)]
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from thymio_bt.plan.model import NodePlan


def subtree_uses(plan: NodePlan, parent: str = "") -> Iterator[tuple[str, NodePlan]]:
    """(node path, node) of every subtree use in ``plan``, in pre-order."""
    path = f"{parent}/{plan.name}" if parent else plan.name
    if plan.subtree is not None:
        yield path, plan
    for child in plan.children:
        yield from subtree_uses(child, path)


@dataclass(frozen=True)
class Phase:
    """One subtree use that ran: its ``name`` and node ``path``, ``start``, ``end`` and ``duration``
    (simulated s), the ``status`` of its last behaviour's event, and ``cells``: how many different
    maze cells its behaviours reported (the mapping behaviours; else None)."""

    name: str
    path: str
    start: float
    end: float
    duration: float
    status: str | None
    cells: int | None = None

    def as_dict(self) -> dict[str, str | float | None]:
        """As the report writes it (``cells`` only when there are some)."""
        entry: dict[str, str | float | None] = {
            "name": self.name,
            "path": self.path,
            "start": self.start,
            "end": self.end,
            "duration": self.duration,
            "status": self.status,
        }
        return entry if self.cells is None else entry | {"cells": self.cells}


def phases(plan: NodePlan, events: list[dict[str, Any]]) -> list[Phase]:
    """One :class:`Phase` per subtree use that ran, from the run's events."""
    out = []
    for path, node in subtree_uses(plan):
        inside = [e for e in events if str(e.get("path", "")).startswith(path + "/")]
        if not inside:
            continue
        start, end = inside[0]["t"], inside[-1]["t"]
        cells = {tuple(e["cell"]) for e in inside if isinstance(e.get("cell"), list)}
        status = inside[-1].get("status")
        out.append(Phase(node.name, path, start, end, round(end - start, 6), status, len(cells) or None))
    return out
