"""The assemble pass: one mission file and what it pulls in, put together and checked.

From the YAML read with marks, it loads plugins, includes (recursively), parameters, subtrees and the
settings (tick rate, time limit, seed, noise, sensor model, robot, backend, and ``--set``
overrides: :mod:`thymio_bt.mission.settings`), then the maze and the start pose. What comes out, an
:class:`Assembly`, is what the planning pass needs to turn the ``tree:`` into a
:class:`~thymio_bt.plan.model.NodePlan`.

Example::

    >>> from thymio_bt.inputs.yamlio import load_yaml
    >>> from thymio_bt.mission.loader import resolve_mission
    >>> path = resolve_mission("maze_part1_2")
    >>> assembly = Assembler().assemble(path, load_yaml(path))
    >>> assembly.problems, assembly.start, assembly.maze.name
    ([], Pose(x=0.1, y=0.1, yaw=0.0), 'two_parts_maze')
    >>> sorted(assembly.subtrees), [p.name for p in assembly.sources]
    (['to_dead_end'], ['maze_part1_2.yaml', 'maze_legs.yaml', 'two_parts_maze.yaml'])
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.geometry import Pose
from thymio_bt.inputs.yamlio import MarkedDict, load_yaml, mark_of
from thymio_bt.maze import Maze, load_maze, resolve_maze
from thymio_bt.mission.pass_base import Scope, Where
from thymio_bt.mission.settings import MAX_SEED, SETTING_RANGES, SettingsReader
from thymio_bt.plan.registry import Registry, default_registry
from thymio_bt.robot.model import DEFAULT_ROBOT, RobotModel, robot_model
from thymio_bt.robot.placement import placement_problem

__all__ = [
    "INCLUDE_KEYS",
    "MAX_SEED",
    "SETTING_RANGES",
    "TOP_KEYS",
    "Assembler",
    "Assembly",
    "Subtree",
]

TOP_KEYS = (
    "name",
    "description",
    "maze",
    "start",
    "tick_hz",
    "time_limit",
    "seed",
    "noise",
    "sensor_model",
    "robot",
    "backend",
    "expect",
    "parameters",
    "subtrees",
    "include",
    "plugins",
    "tree",
)
INCLUDE_KEYS = ("description", "parameters", "subtrees", "include", "plugins")


@dataclass
class Subtree:
    """A subtree defined under ``subtrees:``: its body (parameters and tree) and where it was written."""

    name: str
    body: Any
    where: Where


@dataclass
class Assembly:
    """One mission file with its includes, parameters, settings, subtrees, maze and start, checked."""

    path: Path
    data: MarkedDict
    registry: Registry
    problems: list[Problem]
    parameters: dict[str, Any]
    settings: dict[str, Any]
    subtrees: dict[str, Subtree]
    maze: Maze | None
    maze_file: Path | None
    start: Pose | None
    start_where: Where
    #: every file the mission was read from: itself, its includes, its maze and its .py plugins
    sources: tuple[Path, ...] = ()
    #: each included file and where it was included (file, line, column)
    included_at: dict[Path, Where] = field(default_factory=dict)
    #: the robot asked for was refused (that is reported already)
    robot_refused: bool = False

    @property
    def robot(self) -> RobotModel | None:
        """The mission's robot model (None when the one asked for was refused)."""
        return None if self.robot_refused else robot_model(self.settings.get("robot"))


class Assembler(SettingsReader):
    """Runs the assemble pass over one mission file."""

    def __init__(self, registry: Registry | None = None, run_plugins: bool = True) -> None:
        super().__init__([])
        self.registry = (registry or default_registry()).copy()
        self.run_plugins = run_plugins
        self.subtrees: dict[str, Subtree] = {}
        self.included_parameters: list[tuple[MarkedDict, str]] = []
        #: each included file, with where it was first included (the place of its ``include:`` item)
        self.included: dict[Path, Where] = {}

    def assemble(
        self,
        path: Path,
        data: Any,
        overrides: Mapping[str, str] | None = None,
        maze_override: str | Path | None = None,
        start_override: str | None = None,
    ) -> Assembly:
        """Put the mission ``data`` read from ``path`` together; problems are collected, not raised."""
        file = str(path)
        if not isinstance(data, MarkedDict):
            line, column = mark_of(data, (1, 1))
            raise UserError(
                Problem(
                    "a mission file must be a mapping with at least 'maze:', 'start:' and 'tree:'",
                    file,
                    line,
                    column,
                    hint="see missions/maze_part1_2.yaml for an example",
                )
            )
        self.check_keys(data, TOP_KEYS, file, "", "the mission")
        self._plugins(data, path)
        self._includes(data, path, [path.resolve()])
        params = self._parameters(data, file)
        settings = self._settings(data, file, params, overrides or {})
        self._subtrees(data, file)
        maze, maze_file = self._maze(data, path, maze_override)
        start = self._start(
            data, file, maze, start_override, None if self.robot_refused else settings.get("robot", DEFAULT_ROBOT)
        )
        start_where = ("--start", 0, 0) if start_override is not None else self.where_value(data, "start", file)
        if settings.get("expect") is not None and (maze_override is not None or start_override is not None):
            # places are the mission's own maze's: elsewhere only the place-free criteria hold
            settings["expect"] = settings["expect"].without_places()
        sources = (path, *sorted(self.included), *([maze_file] if maze_file else []), *self.registry.plugin_files)
        return Assembly(
            path,
            data,
            self.registry,
            self.problems,
            params,
            settings,
            self.subtrees,
            maze,
            maze_file,
            start,
            start_where,
            sources,
            dict(self.included),
            self.robot_refused,
        )

    def _plugins(self, data: MarkedDict, path: Path) -> None:
        """The ``plugins:`` of ``data`` (read from ``path``), loaded into the registry (or declared, unrun)."""
        file = str(path)
        plugins = data.get("plugins", [])
        if isinstance(plugins, str):
            plugins = [plugins]
        if not isinstance(plugins, list):
            self.problem(
                "plugins: must be a list of 'module:Class' or file.py paths",
                self.where_value(data, "plugins", file),
                "plugins",
            )
            return
        for i, ref in enumerate(plugins):
            where = self.where_item(plugins, i, self.where_value(data, "plugins", file))
            if not isinstance(ref, str):
                self.problem("a plugin is a string: 'module:Class' or a .py path", where, f"plugins[{i}]")
                continue
            try:
                self.registry.load_plugin(ref, path.parent, where, run=self.run_plugins)
            except UserError as exc:
                self.problems.extend(exc.problems)

    def _includes(self, data: MarkedDict, path: Path, stack: list[Path]) -> None:
        """The files ``include:``d by ``data`` (read from ``path``), each once; ``stack``: the files
        including this one, outermost first (a file among them is a cycle)."""
        file = str(path)
        includes = data.get("include", [])
        if isinstance(includes, str):
            includes = [includes]
        if not isinstance(includes, list):
            self.problem(
                "include: must be a file name or a list of them", self.where_value(data, "include", file), "include"
            )
            return
        for i, ref in enumerate(includes):
            where = self.where_item(includes, i, self.where_value(data, "include", file))
            if not isinstance(ref, str) or not ref.strip() or "\0" in ref:
                self.problem(
                    "an include is a file path (relative to this file)",
                    where,
                    f"include[{i}]",
                    "e.g. include: lib/maze_legs.yaml",
                )
                continue
            self._include(ref, path, where, f"include[{i}]", stack)

    def _include(self, ref: str, path: Path, where: Where, at: str, stack: list[Path]) -> None:
        """One included file ``ref`` (relative to ``path``): its plugins, includes and subtrees; its
        parameters are read later, before the including file's."""
        shown = Path(os.path.normpath(path.parent / ref))  # as the user would write it ...
        try:
            target = (path.parent / ref).resolve()
        except (RuntimeError, OSError):  # Python 3.11 raises RuntimeError for a loop of links
            self.problem(
                f"included file {shown} is a loop of symbolic links",
                where,
                at,
                "point the include at a real file",
            )
            return
        if shown.resolve() != target:
            shown = target  # ... unless symbolic links disagree
        if target in stack:
            cycle = " -> ".join(p.name for p in [*stack[stack.index(target) :], target])
            self.problem(
                f"include cycle: {cycle}",
                where,
                at,
                "a file may not include itself, directly or through others",
            )
            return
        if target in self.included:
            return  # included twice (e.g. by two included files): once is enough
        self.included[target] = where
        if not target.exists():
            self.problem(
                f"included file not found: {shown}",
                where,
                at,
                "include paths are relative to the including file" + _file_suggestion(shown),
            )
            return
        try:
            included = load_yaml(shown, "include")
        except UserError as exc:
            self.adopt(exc.problems, where, at)
            return
        if not isinstance(included, MarkedDict):
            self.problem(
                "an included file must be a mapping with 'subtrees:'",
                (str(shown), *mark_of(included, (1, 1))),
                "",
                "e.g. missions/lib/maze_legs.yaml",
            )
            return
        self.check_keys(included, INCLUDE_KEYS, str(shown), "", "an included file")
        self._plugins(included, shown)
        self._includes(included, shown, [*stack, target])
        self._subtrees(included, str(shown))
        self.included_parameters.append((included, str(shown)))

    def _parameters(self, data: MarkedDict, file: str) -> dict[str, Any]:
        """The mission's parameters: the included files' first, then its own (a later one wins)."""
        params: dict[str, Any] = {}
        sources = [*self.included_parameters, (data, file)]
        for source, source_file in sources:
            raw = source.get("parameters", {})
            if raw is None:
                continue
            if not isinstance(raw, dict):
                self.problem(
                    "parameters: must be a mapping of name: value",
                    self.where_value(source, "parameters", source_file),
                    "parameters",
                )
                continue
            for name, value in raw.items():
                if not isinstance(name, str) or not name.isidentifier():
                    self.problem(
                        f"parameter name {name!r} must be a plain identifier",
                        self.where_key(raw, name, source_file),
                        "parameters",
                    )
                    continue
                params[name] = self.parameter_value(
                    value, self.where_value(raw, name, source_file), f"parameters.{name}"
                )
        return params

    def _subtrees(self, data: MarkedDict, file: str) -> None:
        """The ``subtrees:`` of ``data``, checked and recorded (a name is defined once, in any file)."""
        raw = data.get("subtrees") or MarkedDict()
        if not isinstance(raw, dict):
            self.problem(
                "subtrees: must be a mapping of name: {parameters, tree}",
                self.where_value(data, "subtrees", file),
                "subtrees",
            )
            return
        for name, body in raw.items():
            where = self.where_key(raw, name, file)
            if not isinstance(name, str) or not name.isidentifier():
                self.problem(f"subtree name {name!r} must be a plain identifier", where, "subtrees")
                continue
            if name in self.registry:
                self.problem(
                    f"subtree name '{name}' is already a behaviour, composite or decorator",
                    where,
                    f"subtrees.{name}",
                    "choose another name",
                )
                continue
            if name in self.subtrees:
                first = self.subtrees[name].where
                self.problem(
                    f"subtree '{name}' is defined twice (first at {first[0]}:{first[1]})", where, f"subtrees.{name}"
                )
                continue
            if not isinstance(body, MarkedDict) or "tree" not in body:
                self.problem(
                    f"subtree '{name}' needs a 'tree:' (and optional 'parameters:')", where, f"subtrees.{name}"
                )
                continue
            self.check_keys(body, ("parameters", "tree", "description"), file, f"subtrees.{name}", "a subtree")
            declared = body.get("parameters")
            if isinstance(declared, MarkedDict) and "name" in declared:
                self.problem(
                    f"subtree '{name}' has a parameter called 'name', which no use can set: 'name:' is the "
                    "label of the node where the subtree is used",
                    self.where_key(declared, "name", file),
                    f"subtrees.{name}.parameters.name",
                    "call it what it names (e.g. entity or target)",
                )
            self.subtrees[name] = Subtree(name, body, (file, *body.mark))

    def _maze(self, data: MarkedDict, path: Path, override: str | Path | None) -> tuple[Maze | None, Path | None]:
        """The maze (``maze:`` or ``--maze``) and its file, or (None, None) and a problem."""
        file = str(path)
        if override is not None:
            ref, base, where = str(override), None, ("--maze", 0, 0)
        elif "maze" in data:
            ref, base, where = data["maze"], path.parent, self.where_value(data, "maze", file)
        else:
            self.problem(
                "missing required key 'maze'",
                (file, *data.mark),
                "",
                "name a maze (e.g. two_parts_maze) or give a path relative to this file",
            )
            return None, None
        if not isinstance(ref, str):
            self.problem("maze: must be a maze name or a file path", where, "maze")
            return None, None
        try:
            maze_file = resolve_maze(ref, base)
            return load_maze(maze_file), maze_file
        except UserError as exc:
            self.adopt(exc.problems, where, "maze")
            return None, None

    def _start(
        self, data: MarkedDict, file: str, maze: Maze | None, override: str | None, robot: str | None
    ) -> Pose | None:
        """The start pose (``start:`` or ``--start``): a spawn name or a pose, free of ``robot``'s hull
        and the walls (not checked when the robot was refused)."""
        if override is not None:
            where: Where = ("--start", 0, 0)
            raw: Any = override
        elif "start" in data:
            where, raw = self.where_value(data, "start", file), data["start"]
        else:
            self.problem(
                "missing required key 'start'",
                (file, *data.mark),
                "",
                "a named spawn of the maze (e.g. part1) or [x, y, yaw]",
            )
            return None
        pose = self.pose(raw, where, "start", Scope({}), maze)
        if pose is not None and maze is not None and robot is not None:
            problem = placement_problem(maze, robot_model(robot), pose)
            if problem:
                self.problem(
                    f"impossible start pose: {problem}",
                    where,
                    "start",
                    "pick a free pose inside the maze"
                    + (f", e.g. one of its spawns: {', '.join(maze.spawns)}" if maze.spawns else ""),
                )
                return None
        return pose


def _file_suggestion(missing: Path) -> str:
    """'; did you mean 'maze_legs.yaml'?' when a YAML file of a close name sits beside a missing one."""
    try:
        names = [p.name for p in missing.parent.glob("*.yaml")] if missing.parent.is_dir() else []
    except OSError:
        return ""
    return "; " + did_you_mean(missing.name, names) if names else ""
