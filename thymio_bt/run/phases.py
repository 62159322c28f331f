"""A run's phases: each use of a mission subtree (``subtrees:``), when it ran and what it saw.

A mission such as ``micromouse.yaml`` is written as phases (search, return, fast run); its report
says how long each took, from the behaviours' events, so nobody has to read them to find out.

Example:

>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import run_mission
>>> result = run_mission(load_mission("micromouse"))
>>> [(p["name"], p["duration"], p["cells"]) for p in result.phases]
[('search', 45.2, 11), ('return', 70.2, 14), ('fast run', 36.5, 9)]
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from thymio_bt.plan.model import NodePlan


def subtree_uses(plan: NodePlan, parent: str = "") -> Iterator[tuple[str, NodePlan]]:
    """(node path, node) of every subtree use in ``plan``, in pre-order."""
    path = f"{parent}/{plan.name}" if parent else plan.name
    if plan.subtree is not None:
        yield path, plan
    for child in plan.children:
        yield from subtree_uses(child, path)


def phases(plan: NodePlan, events: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One entry per subtree use that ran: ``name``, ``path``, ``start``, ``end``,
    ``duration`` (simulated s), ``status`` (of its last behaviour) and ``cells`` (how many different
    maze cells its behaviours reported, for the mapping behaviours; else absent)."""
    out = []
    for path, node in subtree_uses(plan):
        inside = [e for e in events if str(e.get("path", "")).startswith(path + "/")]
        if not inside:
            continue
        start, end = inside[0]["t"], inside[-1]["t"]
        entry: dict[str, Any] = {
            "name": node.name,
            "path": path,
            "start": start,
            "end": end,
            "duration": round(end - start, 6),
            "status": inside[-1].get("status"),
        }
        cells = {tuple(e["cell"]) for e in inside if isinstance(e.get("cell"), list)}
        if cells:
            entry["cells"] = len(cells)
        out.append(entry)
    return out
