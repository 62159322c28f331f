"""Helpers to test behaviours and subtrees on small worlds (also a pytest plugin: see ``conftest``).

Example (a student's test: pytest runs it; here it is called):

>>> from thymio_bt.testing import run_tree, world
>>> def test_stops_five_cm_from_the_wall():
...     result = run_tree({"MoveUntilWall": {"distance": "5cm"}}, world("corridor"), seconds=20)
...     assert result.status == "SUCCESS"
...     assert abs(result.final_proximity["front_center"] - 0.05) < 0.001
>>> test_stops_five_cm_from_the_wall()

A tree that fails says which node and why, and every node's statistics come with the result:

>>> result = run_tree({"sequence": [{"MoveDistance": {"distance": "2m"}}, "Stop"]}, world("corridor"))
>>> result.status, result.code, result.failed_path, result.reason
(<RunStatus.FAILURE: 'FAILURE'>, <FailureCode.COLLISION: 'COLLISION'>, 'sequence/MoveDistance', 'the robot hit a wall')
>>> result.node_stats["sequence/MoveDistance"]
{'ticks': 65, 'successes': 0, 'failures': 1, 'running_time': 6.4}

A behaviour of your own comes in through ``plugins``: the class itself, a ``.py`` file (a relative
path is relative to the calling test's file) or ``"package.module:Class"``:

>>> from py_trees.common import Status
>>> from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour
>>> class Creep(RobotBehaviour):
...     '''Drive slowly for ever.'''
...     Params, moves = BehaviourParams, True
...     def step(self):
...         self.robot.drive(0.02, 0.0)
...         return Status.RUNNING
>>> result = run_tree("Creep", world("arena"), seconds=2, plugins=[Creep])
>>> result.status, round(result.final_pose.x, 2)  # from x = 0.7
(<RunStatus.TIMEOUT: 'TIMEOUT'>, 0.74)
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import py_trees
import yaml

from thymio_bt.errors import UserError, did_you_mean
from thymio_bt.maze import Maze, maze_from_grid
from thymio_bt.run.runner import Run, RunResult

if TYPE_CHECKING:
    from thymio_bt.logs.entries import Recording
    from thymio_bt.plan.registry import Registry

#: a plugin as :func:`run_tree` takes it: a ``.py`` path, ``"package.module:Class"``, or the class
Plugin = str | Path | type

#: Small worlds of 0.2 m cells; ``>`` marks the start (base_link at the cell centre).
PRESETS: dict[str, str] = {
    "corridor": """
+--+--+--+--+
|>          |
+--+--+--+--+
""",
    "L": """
+--+--+--+
|>       |
+--+--+  +
      |  |
      +--+
""",
    "T": """
+--+--+--+
|        |
+--+  +--+
   |^ |
   +--+
""",
    "pocket": """
+--+--+--+
|>    |  |
+--+--+--+
""",
    "arena": """
+--+--+--+--+--+--+
|                 |
+  +  +  +  +  +  +
|                 |
+  +  +  +  +  +  +
|                 |
+  +  +  +  +  +  +
|         >       |
+  +  +  +  +  +  +
|                 |
+  +  +  +  +  +  +
|                 |
+--+--+--+--+--+--+
""",
}


def world(preset_or_grid: str, cell: float = 0.2) -> Maze:
    """A preset world (corridor, L, T, pocket, arena) or a grid drawn in ASCII (see maze.grid)."""
    if preset_or_grid not in PRESETS and "\n" not in preset_or_grid.strip():
        raise UserError(
            f"no preset world named '{preset_or_grid}' (hint: {did_you_mean(preset_or_grid, PRESETS)}, "
            f"or draw one as a grid of several lines)"
        )
    text = PRESETS.get(preset_or_grid, preset_or_grid)
    return maze_from_grid(text, cell=cell, name=preset_or_grid if preset_or_grid in PRESETS else "grid")


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def mission_text(tree: Any, maze_file: str, start: Any = "start", seconds: float = 60.0, **settings: Any) -> str:
    """The YAML text of a one-tree mission (useful to test the loader too)."""
    doc = {
        "name": "test",
        "maze": maze_file,
        "start": _plain(start),
        "time_limit": seconds,
        **{k: _plain(v) for k, v in settings.items() if v is not None},
        "tree": _plain(tree),
    }
    return yaml.safe_dump(doc, sort_keys=False)


def run_tree(
    tree: Any,
    maze: Maze,
    start: Any = "start",
    seconds: float = 60.0,
    seed: int = 0,
    substitute: dict[str, Any] | None = None,
    plugins: Sequence[Plugin] = (),
    **settings: Any,
) -> RunResult:
    """Run ``tree`` (a node as written in mission YAML, as a dict or YAML text) for at most
    ``seconds`` of simulated time in ``maze``; returns the run report's :class:`RunResult` with
    per-node statistics in ``result.node_stats``.

    ``plugins`` are behaviours from outside the package, as a mission's ``plugins:`` lists them: a
    ``.py`` file (a relative path is relative to the folder of the file that calls ``run_tree``,
    your test), ``"package.module:Class"``, or the class itself. ``substitute`` maps node-path
    globs to scripted stubs (see :func:`run_mission_file`); ``settings`` are more mission keys:
    ``parameters``, ``subtrees``, ``noise``, ``tick_hz``.

    A tree or parameter that the mission loader refuses raises :class:`~thymio_bt.errors.UserError`,
    its problems located at the line of your test that called ``run_tree`` (the node's path says
    where in the tree), as ``pytest`` shows it:

    >>> try:
    ...     run_tree({"MoveUntilWall": {"distanse": "5cm"}}, world("corridor"))
    ... except UserError as exc:
    ...     print(exc.problems[0].message, "|", exc.problems[0].path, "|", exc.problems[0].hint)
    MoveUntilWall has no parameter 'distanse' | tree.MoveUntilWall.distanse | did you mean 'distance'?
    """
    from thymio_bt.mission import load_mission

    if isinstance(tree, str):
        tree = yaml.safe_load(tree)
    caller = _caller()
    registry, refs = _plugins(plugins, caller.file if caller.line == 0 else caller.file.parent)
    with tempfile.TemporaryDirectory(prefix="thymio-bt-test-") as tmp:
        maze_file = Path(tmp) / "maze.yaml"
        maze_file.write_text(yaml.safe_dump(maze.to_yaml_dict(), sort_keys=False))
        mission_file = Path(tmp) / "mission.yaml"
        mission_file.write_text(mission_text(tree, maze_file.name, start, seconds, plugins=refs or None, **settings))
        try:
            mission = load_mission(mission_file, registry=registry)
        except UserError as exc:  # the temporary files mean nothing to the test's author: point at the call
            here = Path(tmp).resolve()
            raise UserError(
                replace(p, file=str(caller.file), line=caller.line, column=0)
                if caller.line and here in Path(p.file).resolve().parents
                else p
                for p in exc.problems
            ) from None
    return Run(mission, seed, substitutions=substitute, node_stats=True).run()


@dataclass(frozen=True)
class _Call:
    """Where a helper was called from: the file (a test) and the line of the call."""

    file: Path
    line: int


def _caller() -> _Call:
    """The nearest calling file outside thymio-bt (a test) and the line of its call; the working
    folder (line 0) when there is none (an interactive session)."""
    package = Path(__file__).resolve().parent
    frame = sys._getframe(1)
    while frame is not None:
        file = Path(frame.f_code.co_filename)
        if not file.name.startswith("<") and package not in file.resolve().parents:
            return _Call(file.resolve(), frame.f_lineno)
        frame = frame.f_back  # type: ignore[assignment]
    return _Call(Path.cwd(), 0)


def _plugins(plugins: Sequence[Plugin], folder: Path) -> tuple[Registry | None, list[str]]:
    """A registry with the plugin classes among ``plugins`` (None: none), and the others as a
    mission's ``plugins:`` entries, a relative ``.py`` path made absolute from ``folder``."""
    from thymio_bt.plan.registry import default_registry

    registry, refs = None, []
    for plugin in plugins:
        if isinstance(plugin, type):
            registry = registry or default_registry().copy()
            try:
                registry.register(plugin)
            except (TypeError, ValueError) as exc:
                raise UserError(f"plugins: {exc}") from None
        elif str(plugin).endswith(".py"):
            path = folder / plugin
            if not path.is_file():
                raise UserError(
                    f"plugin file not found: {plugin} (hint: a relative path is relative to the calling "
                    f"test's folder, {folder}; or pass the behaviour's class itself)"
                )
            refs.append(str(path.resolve()))
        else:
            refs.append(str(plugin))
    return registry, refs


def run_mission_file(
    path: str | Path,
    substitute: dict[str, Any] | None = None,
    seed: int | None = None,
    overrides: dict[str, str] | None = None,
    **options: Any,
) -> RunResult:
    """Run a mission file with parts replaced: ``substitute`` maps glob patterns on node paths
    (names from the root joined by ``/``, e.g. ``"course/part 2/*"`` or ``"*/DeleteEntity"``) to a
    status (``"success"``), a list of statuses one per tick, or ``{"status": ..., "seconds": ...}``.

    Example (part 2 replaced by a stub that succeeds at once):

    >>> result = run_mission_file("maze_part1_2", substitute={"course/part 2": "success"})
    >>> result.status, result.ticks, result.node_stats["course/part 2"]
    (<RunStatus.SUCCESS: 'SUCCESS'>, 46, {'ticks': 1, 'successes': 1, 'failures': 0, 'running_time': 0.0})
    """
    from thymio_bt.mission import load_mission

    mission = load_mission(path, overrides, **options)
    return Run(mission, seed, substitutions=substitute, node_stats=True).run()


def recorded(mission: str | Path = "square", log_path: str | Path | None = None) -> Recording:
    """A mission run and recorded tick by tick (and logged to ``log_path``, its suffix the format):
    what plots, animations and log readers are shown and tested with.

    >>> recording = recorded("square")
    >>> len(recording.samples), recording.end["status"]
    (228, <RunStatus.SUCCESS: 'SUCCESS'>)
    """
    from thymio_bt.logs.recording import Recorder
    from thymio_bt.mission import load_mission

    recorder = Recorder(log_path=log_path)
    return recorder.finish(Run(load_mission(mission)).run(on_tick=recorder))


def clear_blackboard() -> Iterator[None]:
    """A fixture body: clear py_trees' global blackboard before and after a test."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


__all__ = ["PRESETS", "Plugin", "clear_blackboard", "mission_text", "recorded", "run_mission_file", "run_tree", "world"]
