"""Which nodes a submission may use: an assignment's ``palette`` checked on the mission's plan,
read without running any of its code. Each rule broken is a :class:`Finding` naming the node
and its file:line, and costs the palette's ``penalty``.

Example::

    >>> from thymio_bt.grade.assignment import Palette
    >>> from thymio_bt.mission.loader import load_mission
    >>> mission = load_mission("maze_6x6_left", run_plugins=False)
    >>> [f.message for f in check_palette(mission, Palette(forbid=["WallFollow"], penalty=5))]
    ['WallFollow is not allowed in this assignment']
    >>> check_palette(mission, Palette(allow=["WallFollow"]))
    []
"""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from thymio_bt.data import MISSIONS
from thymio_bt.grade.assignment import Palette
from thymio_bt.plan.model import Mission, NodePlan


@dataclass(frozen=True)
class Finding:
    """A palette rule a submission breaks."""

    rule: str
    node: str | None
    where: str | None
    message: str
    points: float

    def to_json(self) -> dict[str, Any]:
        """As in results.json's ``palette`` list."""
        return asdict(self)


def node_type(node: NodePlan) -> str:
    """What a palette names a node by: its behaviour, or its composite or decorator kind."""
    return node.behaviour or node.kind


def where(node: NodePlan) -> str | None:
    """``file:line`` of the node in its file, when known."""
    file, line, _ = node.where
    return f"{file}:{line}" if file else None


def wheres(tree: NodePlan) -> dict[str, str | None]:
    """``file:line`` of each node by its path in the running tree (names from the root, as run
    reports and events say: ``course/part 1``); the first of two same-named siblings."""
    found: dict[str, str | None] = {}

    def visit(node: NodePlan, prefix: str) -> None:
        path = f"{prefix}/{node.name}" if prefix else node.name
        found.setdefault(path, where(node))
        for child in node.children:
            visit(child, path)

    visit(tree, "")
    return found


def check_palette(mission: Mission, palette: Palette) -> list[Finding]:
    """The rules of ``palette`` that ``mission`` breaks, each once, in the tree's order."""
    findings: dict[tuple[str, str | None], Finding] = {}

    def add(rule: str, node: str | None, at: str | None, message: str) -> None:
        findings.setdefault((rule, node), Finding(rule, node, at, message, palette.penalty))

    depth_of: dict[str, int] = {}
    for node in mission.tree.walk():
        parent = node.path.rpartition("/")[0]
        depth_of[node.path] = depth_of.get(parent, 0) + 1
        kind = node_type(node)
        if kind in palette.forbid:
            add("forbid", kind, where(node), f"{kind} is not allowed in this assignment")
        elif palette.allow is not None and kind not in palette.allow:
            add("allow", kind, where(node), f"{kind} is not in this assignment's palette ({', '.join(palette.allow)})")
    nodes = len(depth_of)
    if palette.max_nodes is not None and nodes > palette.max_nodes:
        add("max_nodes", None, where(mission.tree), f"the tree has {nodes} nodes, at most {palette.max_nodes} allowed")
    depth = max(depth_of.values())
    if palette.max_depth is not None and depth > palette.max_depth:
        add("max_depth", None, where(mission.tree), f"the tree is {depth} deep, at most {palette.max_depth} allowed")
    if not palette.plugins:
        for ref, (file, line, _) in mission.registry.plugins:  # files and modules alike: both run code
            name = Path(ref).name if ref.endswith(".py") else ref
            add("plugins", ref, f"{file}:{line}", f"plugins are not allowed in this assignment ({name})")
    if not palette.include_library:
        library = _library()
        for source in mission.sources[1:]:
            if source.suffix in (".yaml", ".yml") and _digest(source) in library:
                file, line, _ = mission.included_at.get(source, (str(source), 0, 0))
                at = f"{file}:{line}" if line else file
                add("include_library", None, at, f"includes the shipped library file {source.name}")
    return list(findings.values())


def _library() -> set[str]:
    """The digests of the shipped missions' library files (a copy is the same file)."""
    return {_digest(p) for p in (MISSIONS / "lib").glob("*.y*ml")}


def _digest(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return ""
