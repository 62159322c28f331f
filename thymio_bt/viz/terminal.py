"""The tree in the terminal: live statuses while a run goes, the failing branch after it,
and exports to Graphviz (.dot always; .svg/.png when Graphviz's ``dot`` program is installed).

Example:

>>> print(tree_text(Path("square")).rstrip())  # the mission's repeat, a sequence and two leaves
-^- four sides
    {-} side
        --> MoveDistance
        --> TurnAngle
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import py_trees

from thymio_bt.errors import UserError

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from thymio_bt.outputs import Output
    from thymio_bt.run.runner import Run


class LiveTree:
    """An ``on_tick`` hook printing the tree with statuses and feedback whenever a status changes."""

    def __init__(self, stream: Any = None) -> None:
        self.stream = stream or sys.stdout
        self.last: tuple[Any, ...] | None = None
        self.clear = self.stream.isatty() if hasattr(self.stream, "isatty") else False

    def __call__(self, run: Run) -> None:
        """Print the tree if any node's status changed with this tick."""
        state = tuple((n.id, n.status) for n in run.root.iterate())
        if state == self.last:
            return
        self.last = state
        text = py_trees.display.unicode_tree(run.root, show_status=True)
        prefix = "\x1b[H\x1b[2J" if self.clear else ""
        self.stream.write(f"{prefix}t = {run.backend.time():.1f} s\n{text}\n")
        self.stream.flush()


def failing_tree(run: Run) -> str:
    """The tree with the statuses it had when the run ended, for the end of a failed run."""
    return "the tree when the run ended:\n" + run.final_tree


def _build(mission_path: Path, run_plugins: bool = False) -> Behaviour:
    """The mission's py_trees tree, to draw: built with no robot (behaviours touch it only when ticked);
    its plugins are read, not imported, unless ``run_plugins``."""
    from thymio_bt.behaviours import Context
    from thymio_bt.mission import build_tree, load_mission

    mission = load_mission(mission_path, run_plugins=run_plugins)
    nobody = Context(robot=None, entities=None)  # type: ignore[arg-type]  # drawn, never ticked: no robot needed
    return build_tree(mission.tree, nobody, mission.registry)


def tree_text(mission_path: Path, run_plugins: bool = False) -> str:
    """The mission's tree as py_trees draws it in a terminal (``thymio-bt tree``)."""
    return py_trees.display.unicode_tree(_build(mission_path, run_plugins))


def export_tree(mission_path: Path, out: Output, fmt: str, run_plugins: bool = False) -> None:
    """Write the tree to ``out`` as Graphviz .dot text, or as .svg/.png drawn by Graphviz's ``dot``."""
    source = py_trees.display.dot_tree(_build(mission_path, run_plugins)).to_string()
    if fmt == "dot":
        out.write_text(source)
        return
    program = shutil.which("dot")
    if program is None:
        raise UserError(
            f"a .{fmt} needs Graphviz's 'dot' program (hint: apt-get install graphviz, "
            f"or write the .dot: thymio-bt tree {mission_path} --dot -o {Path(str(out)).stem}.dot)"
        )
    if out.is_stdout:
        sys.stdout.buffer.write(
            subprocess.run([program, f"-T{fmt}"], input=source.encode(), check=True, capture_output=True).stdout
        )
        return
    with out.staged() as tmp:
        subprocess.run([program, f"-T{fmt}", "-o", str(tmp)], input=source.encode(), check=True)
