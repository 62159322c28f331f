"""The tree in the terminal: live statuses while a run goes, the failing branch after it,
and exports to Graphviz (.dot always; .svg/.png when Graphviz's ``dot`` program is installed).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import py_trees

from ..errors import UserError


class LiveTree:
    """An ``on_tick`` hook printing the tree with statuses and feedback whenever a status changes."""

    def __init__(self, stream: Any = None) -> None:
        self.stream = stream or sys.stdout
        self.last: tuple[Any, ...] | None = None
        self.clear = self.stream.isatty() if hasattr(self.stream, "isatty") else False

    def __call__(self, run: Any) -> None:
        state = tuple((n.id, n.status) for n in run.root.iterate())
        if state == self.last:
            return
        self.last = state
        text = py_trees.display.unicode_tree(run.root, show_status=True)
        prefix = "\x1b[H\x1b[2J" if self.clear else ""
        self.stream.write(f"{prefix}t = {run.backend.time():.1f} s\n{text}\n")
        self.stream.flush()


def failing_tree(run: Any) -> str:
    """The tree with the statuses it had when the run ended, for the end of a failed run."""
    return "the tree when the run ended:\n" + run.final_tree


def _build(mission_path: Path) -> Any:
    """The mission's py_trees tree, to draw: built with no robot (behaviours touch it only when ticked)."""
    from ..behaviours import Context
    from ..mission import build_tree, load_mission

    mission = load_mission(mission_path)
    return build_tree(mission.tree, Context(robot=None, entities=None), mission.registry)  # type: ignore[arg-type]


def tree_text(mission_path: Path) -> str:
    return py_trees.display.unicode_tree(_build(mission_path))


def export_tree(mission_path: Path, fmt: str, output: Path | None) -> tuple[Path, str]:
    """Write the tree as .dot, or .svg/.png through Graphviz; fall back to .dot with a hint."""
    graph = py_trees.display.dot_tree(_build(mission_path))
    target = output or Path(mission_path.stem).with_suffix(f".{fmt}")
    dot_file = target.with_suffix(".dot")
    try:
        dot_file.write_text(graph.to_string())
    except OSError as exc:
        raise UserError(f"cannot write {dot_file}: {exc}") from None
    if fmt == "dot":
        return dot_file, ""
    program = shutil.which("dot")
    if program is None:
        return dot_file, f"no .{fmt}: Graphviz's 'dot' program is not installed " \
                         f"(hint: apt-get install graphviz, then: dot -T{fmt} {dot_file} -o {target})"
    subprocess.run([program, f"-T{fmt}", str(dot_file), "-o", str(target)], check=True)
    return target, ""
