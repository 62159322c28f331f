"""Load a mission file into a validated :class:`~thymio_bt.plan.model.Mission`, in passes:

1. **read** — the YAML with the place of every key and value (:func:`thymio_bt.inputs.yamlio.load_yaml`), or
   a BehaviorTree.CPP XML mission into the same form (:mod:`thymio_bt.btcpp.xml_reader`);
2. **assemble** — includes, plugins, parameters, subtrees, settings and ``--set``, the maze and the
   start pose (:mod:`thymio_bt.mission.assemble`);
3. **validate and plan** — each node of the tree by its registered class and parameter model
   (:mod:`thymio_bt.mission.planner`);
4. **build** — later, against a robot: :func:`thymio_bt.mission.build.build_tree`.

Every problem of a file (and of the files it includes) is collected and reported at once, each
with file:line:col, the node path and a hint.

Example::

    >>> mission = load_mission("maze_part1_2", overrides={"cruise": "0.15 m/s"})
    >>> mission.tree.kind, mission.parameters["cruise"], mission.maze.name
    ('sequence', 0.15, 'two_parts_maze')
    >>> load_mission("maze_part1_2", overrides={"final_stop": "5 parsecs"})
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: ...maze_part1_2.yaml:32:65: parameter '$final_stop' is '5 parsecs', not a number ...
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from thymio_bt.data import MISSIONS
from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.units import Quantity
from thymio_bt.inputs.yamlio import load_yaml
from thymio_bt.mission.assemble import Assembler
from thymio_bt.mission.planner import TreePlanner
from thymio_bt.plan.model import Mission
from thymio_bt.plan.registry import Registry


def resolve_mission(ref: str | Path) -> Path:
    """A mission by path, or by name (``maze_part1_2``): ./missions, then the missions shipped with
    thymio-bt. A name that matches nothing is an error with the nearest names."""
    path = Path(ref)
    if path.exists() or path.suffix or len(path.parts) != 1:
        return path
    folders = [Path("missions"), MISSIONS]
    for folder in folders:
        if (folder / f"{ref}.yaml").is_file():
            return folder / f"{ref}.yaml"
    known = sorted({p.stem for folder in folders if folder.is_dir() for p in folder.glob("*.yaml")})
    raise UserError(
        Problem(
            f"mission not found: '{ref}'", hint=f"a mission file, or a shipped mission: {did_you_mean(str(ref), known)}"
        )
    )


def load_mission(
    path: str | Path,
    overrides: Mapping[str, str] | None = None,
    maze: str | Path | None = None,
    start: str | None = None,
    registry: Registry | None = None,
    run_plugins: bool = True,
) -> Mission:
    """Load and validate a mission file (or a shipped mission by name); raise :class:`UserError`
    listing every problem. ``run_plugins=False`` reads the mission's plugins without importing them
    (see :mod:`thymio_bt.plan.unrun_plugins`): for tools that must not run a stranger's code."""
    path = resolve_mission(path)
    file = str(path)
    if path.suffix.lower() == ".xml":
        from thymio_bt.btcpp.xml_reader import read_xml_mission  # BT.CPP XML: imported only for XML missions

        data = read_xml_mission(path)
    else:
        data = load_yaml(path)
    assembly = Assembler(registry, run_plugins).assemble(path, data, overrides, maze, start)
    tree = TreePlanner(assembly).plan(assembly.data, file)
    if assembly.problems:
        raise UserError(
            sorted(
                dict.fromkeys(assembly.problems),  # in reading order, this file first
                key=lambda p: (p.file != file, p.file, p.line, p.column),
            )
        )
    assert tree is not None and assembly.start is not None and assembly.maze is not None
    data = assembly.data
    return Mission(
        name=str(data.get("name", path.stem)),
        description=str(data.get("description", "")),
        file=path,
        maze=assembly.maze,
        maze_file=assembly.maze_file,
        start=assembly.start,
        tree=tree,
        parameters={k: (v.value if isinstance(v, Quantity) else v) for k, v in assembly.parameters.items()},
        registry=assembly.registry,
        start_where=assembly.start_where,
        sources=assembly.sources,
        included_at=assembly.included_at,
        **assembly.settings,
    )
