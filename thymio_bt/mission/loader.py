"""Load a mission file into a validated :class:`~thymio_bt.mission.plan.Mission`.

Every problem of a file (and of the files it includes) is collected and reported at once, each
with file:line:col, the node path and a hint. See ``docs`` in README "Write your own mission".

Example::

    mission = load_mission("missions/maze_part1_2.yaml", overrides={"cruise": "0.15 m/s"})
    mission.tree.kind          # 'sequence'
"""

from __future__ import annotations

import os
import types
import typing
from pathlib import Path
from typing import Any, Mapping

from pydantic import BaseModel, ValidationError

from ..behaviours import ControlNode
from ..errors import Problem, UserError, did_you_mean, type_name
from ..fields import SpawnName, Unit, field_metadata, metadata, unit_of
from ..maze import Maze, load_maze, resolve_maze
from ..placement import placement_problem
from ..robot import Pose
from ..robot_model import ROBOTS, robot_model
from ..sim.noise import NoiseConfig
from ..units import Quantity, UnitError, check_kind, kind_hint, parse_pose, parse_value
from ..validation import problems_from
from ..yamlio import MarkedDict, MarkedList, load_yaml
from .plan import Mission, NodePlan
from .registry import Registry, default_registry

TOP_KEYS = ("name", "description", "maze", "start", "tick_hz", "time_limit", "seed", "noise", "sensor_model",
            "robot", "backend", "parameters", "subtrees", "include", "plugins", "tree")
SENSOR_MODELS = ("metres", "raw")
INCLUDE_KEYS = ("description", "parameters", "subtrees", "include", "plugins")
MAX_DEPTH = 64
#: Most nodes one mission may expand to (subtrees calling subtrees twice each multiply).
MAX_NODES = 20_000

Where = tuple[str, int, int]


class _Scope:
    """Parameter values visible at one place: mission parameters, overlaid by a subtree's."""

    def __init__(self, values: Mapping[str, Any], parent: "_Scope | None" = None) -> None:
        self.values = dict(values)
        self.parent = parent

    def get(self, name: str) -> Any:
        if name in self.values:
            return self.values[name]
        if self.parent is not None:
            return self.parent.get(name)
        raise KeyError(name)

    def names(self) -> set[str]:
        return set(self.values) | (self.parent.names() if self.parent else set())


class _Subtree:
    def __init__(self, name: str, body: Any, where: Where) -> None:
        self.name, self.body, self.where = name, body, where


class MissionLoader:
    """Loads one mission file; collects :class:`Problem` s instead of stopping at the first."""

    def __init__(self, registry: Registry | None = None) -> None:
        self.registry = (registry or default_registry()).copy()
        self.problems: list[Problem] = []
        self.subtrees: dict[str, _Subtree] = {}
        self.maze: Maze | None = None
        self.root_scope = _Scope({})
        self.included_parameters: list[tuple[MarkedDict, str]] = []
        self.node_count = 0
        self.too_deep: set[Where] = set()
        self.included: set[Path] = set()

    # ------------------------------------------------------------ helpers
    def problem(self, message: str, where: Where, path: str = "", hint: str = "") -> None:
        self.problems.append(Problem(message, where[0], where[1], where[2], path, hint))

    @staticmethod
    def where_key(data: Any, key: Any, file: str) -> Where:
        if isinstance(data, MarkedDict) and key in data.marks:
            return (file, *data.marks[key])
        return (file, *getattr(data, "mark", (0, 0)))

    @staticmethod
    def where_value(data: Any, key: Any, file: str) -> Where:
        if isinstance(data, MarkedDict) and key in data.value_marks:
            return (file, *data.value_marks[key])
        if isinstance(data, MarkedList) and isinstance(key, int) and key < len(data.marks):
            return (file, *data.marks[key])
        return (file, *getattr(data, "mark", (0, 0)))

    @staticmethod
    def where_item(items: Any, index: int, where: Where) -> Where:
        """The place of ``items[index]`` when the list carries marks, else ``where`` (the list's)."""
        if isinstance(items, MarkedList) and index < len(items.marks):
            return (where[0], *items.marks[index])
        return where

    def check_keys(self, data: MarkedDict, allowed: typing.Iterable[str], file: str, path: str,
                   what: str) -> None:
        allowed = list(allowed)
        for key in data:
            if key not in allowed:
                self.problem(f"unknown key '{key}' in {what}", self.where_key(data, key, file),
                             path, did_you_mean(str(key), allowed))

    # ------------------------------------------------------------- values
    def quantity(self, value: Any, scope: _Scope, where: Where, path: str, kind: str | None) -> float | None:
        """Parse a number-with-unit or expression in ``scope``; None (and a problem) when it fails."""
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            self.problem(f"expected a number, got {type_name(value)}", where, path,
                         "write a number, optionally with a unit: 0.1, 10cm/s, pi/2, 90deg")
            return None

        def resolve(name: str) -> Quantity:
            try:
                raw = scope.get(name)
            except KeyError:
                raise UnitError(f"unknown parameter '${name}'", _parameter_hint(name, scope)) from None
            if isinstance(raw, Quantity):
                return raw
            if isinstance(raw, (int, float)) and not isinstance(raw, bool):
                return Quantity(float(raw))
            raise UnitError(f"parameter '${name}' is {raw!r}, not a number")

        try:
            q = parse_value(value, resolve)
        except UnitError as exc:
            self.problem(str(exc), where, path, exc.hint or "numbers may carry a unit (5cm, 90deg, 0.1 m/s) "
                         "and use + - * / ( ) pi and $parameters")
            return None
        error = check_kind(q, kind)
        if error:
            self.problem(error, where, path, kind_hint(kind))
            return None
        return q.value

    def parameter_value(self, value: Any, where: Where, path: str) -> Any:
        """A mission or subtree parameter default: a quantity when it parses, else the raw value."""
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return Quantity(float(value))
        if isinstance(value, str):
            try:
                return parse_value(value)
            except UnitError:
                return value
        if isinstance(value, bool):
            return value
        self.problem(f"a parameter must be a number, a string or true/false, got {type_name(value)}",
                     where, path, "e.g. cruise: 10cm/s, side: pi/2, turn: bb:turn_angle or enabled: true")
        return None

    # -------------------------------------------------------------- files
    def load(self, path: str | Path, overrides: Mapping[str, str] | None = None,
             maze_override: str | Path | None = None, start_override: str | None = None) -> Mission:
        path = Path(path)
        file = str(path)
        data = load_yaml(path)
        if not isinstance(data, MarkedDict):
            raise UserError(Problem("a mission file must be a mapping with at least 'maze:', 'start:' and 'tree:'",
                                    file, *getattr(data, "mark", (1, 1)),
                                    hint="see missions/maze_part1_2.yaml for an example"))
        self.check_keys(data, TOP_KEYS, file, "", "the mission")
        self._plugins(data, path)
        self._includes(data, path, [path.resolve()])
        params = self._parameters(data, file)
        settings = self._settings(data, file, params, overrides or {})
        self._subtrees(data, file)
        maze, maze_file = self._maze(data, path, maze_override)
        self.maze = maze
        start = self._start(data, file, maze, start_override, settings.get("robot", "course"))
        start_where = ("--start", 0, 0) if start_override is not None else self.where_value(data, "start", file)
        scope = _Scope(params)
        self.root_scope = scope
        tree = None
        if "tree" not in data:
            self.problem("missing required key 'tree'", (file, *data.mark), "", "the tree is the mission's root node")
        else:
            tree = self.node(data["tree"], self.where_value(data, "tree", file), "tree", scope, 0, ())
        if self.problems:
            raise UserError(sorted(dict.fromkeys(self.problems),      # in reading order, this file first
                                   key=lambda p: (p.file != file, p.file, p.line, p.column)))
        assert tree is not None and start is not None and maze is not None
        return Mission(name=str(data.get("name", path.stem)), description=str(data.get("description", "")),
                       file=path, maze=maze, maze_file=maze_file, start=start, tree=tree,
                       parameters={k: (v.value if isinstance(v, Quantity) else v) for k, v in params.items()},
                       registry=self.registry, start_where=start_where, **settings)

    def _plugins(self, data: MarkedDict, path: Path) -> None:
        file = str(path)
        plugins = data.get("plugins", [])
        if isinstance(plugins, str):
            plugins = [plugins]
        if not isinstance(plugins, list):
            self.problem("plugins: must be a list of 'module:Class' or file.py paths",
                         self.where_value(data, "plugins", file), "plugins")
            return
        for i, ref in enumerate(plugins):
            where = self.where_item(plugins, i, self.where_value(data, "plugins", file))
            if not isinstance(ref, str):
                self.problem("a plugin is a string: 'module:Class' or a .py path", where, f"plugins[{i}]")
                continue
            try:
                self.registry.load_plugin(ref, path.parent, where)
            except UserError as exc:
                self.problems.extend(exc.problems)

    def _includes(self, data: MarkedDict, path: Path, stack: list[Path]) -> None:
        file = str(path)
        includes = data.get("include", [])
        if isinstance(includes, str):
            includes = [includes]
        if not isinstance(includes, list):
            self.problem("include: must be a file name or a list of them",
                         self.where_value(data, "include", file), "include")
            return
        for i, ref in enumerate(includes):
            where = self.where_item(includes, i, self.where_value(data, "include", file))
            if not isinstance(ref, str) or not ref.strip() or "\0" in ref:
                self.problem("an include is a file path (relative to this file)", where, f"include[{i}]",
                             "e.g. include: lib/maze_legs.yaml")
                continue
            target = (path.parent / ref).resolve()
            shown = Path(os.path.normpath(path.parent / ref))     # as the user would write it ...
            if shown.resolve() != target:
                shown = target                                     # ... unless symbolic links disagree
            if target in stack:
                cycle = " -> ".join(p.name for p in [*stack[stack.index(target):], target])
                self.problem(f"include cycle: {cycle}", where, f"include[{i}]",
                             "a file may not include itself, directly or through others")
                continue
            if target in self.included:
                continue                    # included twice (e.g. by two included files): once is enough
            self.included.add(target)
            if not target.is_file():
                self.problem(f"included file not found: {shown}", where, f"include[{i}]",
                             "include paths are relative to the including file"
                             + _file_suggestion(shown))
                continue
            try:
                included = load_yaml(shown)
            except UserError as exc:
                for p in exc.problems:
                    self.problems.append(p if p.line else Problem(p.message, *where, f"include[{i}]", p.hint))
                continue
            if not isinstance(included, MarkedDict):
                self.problem("an included file must be a mapping with 'subtrees:'",
                             (str(shown), *getattr(included, "mark", (1, 1))),
                             "", "e.g. missions/lib/maze_legs.yaml")
                continue
            self.check_keys(included, INCLUDE_KEYS, str(shown), "", "an included file")
            self._plugins(included, shown)
            self._includes(included, shown, [*stack, target])
            self._subtrees(included, str(shown))
            self.included_parameters.append((included, str(shown)))

    def _parameters(self, data: MarkedDict, file: str) -> dict[str, Any]:
        params: dict[str, Any] = {}
        sources = [*self.included_parameters, (data, file)]
        for source, source_file in sources:
            raw = source.get("parameters", {})
            if raw is None:
                continue
            if not isinstance(raw, dict):
                self.problem("parameters: must be a mapping of name: value",
                             self.where_value(source, "parameters", source_file), "parameters")
                continue
            for name, value in raw.items():
                if not isinstance(name, str) or not name.isidentifier():
                    self.problem(f"parameter name {name!r} must be a plain identifier",
                                 self.where_key(raw, name, source_file), "parameters")
                    continue
                params[name] = self.parameter_value(value, self.where_value(raw, name, source_file),
                                                    f"parameters.{name}")
        return params

    def _settings(self, data: MarkedDict, file: str, params: dict[str, Any],
                  overrides: Mapping[str, str]) -> dict[str, Any]:
        empty = _Scope({})
        values: dict[str, Any] = {"tick_hz": 10.0, "time_limit": 300.0, "seed": 0, "sensor_model": "metres"}
        noise_raw: dict[str, Any] = {}
        for key, kind, lo, hi in (("tick_hz", "frequency", 1.0, 100.0), ("time_limit", "time", 0.1, 36000.0)):
            if key in data:
                value = self.quantity(data[key], empty, self.where_value(data, key, file), key, kind)
                if value is not None and not lo <= value <= hi:
                    self.problem(f"{key} must be between {lo:g} and {hi:g}", self.where_value(data, key, file), key)
                elif value is not None:
                    values[key] = value
        if "seed" in data:
            seed = data["seed"]
            if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
                self.problem("seed must be a whole number >= 0", self.where_value(data, "seed", file), "seed",
                             "e.g. seed: 42")
            else:
                values["seed"] = seed
        if "sensor_model" in data:
            self._sensor_model(data["sensor_model"], self.where_value(data, "sensor_model", file), values)
        if "robot" in data:
            self._robot(data["robot"], self.where_value(data, "robot", file), values)
        if "backend" in data:
            self._backend(data["backend"], self.where_value(data, "backend", file), values)
        if "noise" in data:
            noise = data["noise"]
            if isinstance(noise, MarkedDict):
                noise_raw = dict(noise)
            else:
                self.problem("noise: must be a mapping (range_sd, wheel, odometry)",
                             self.where_value(data, "noise", file), "noise")
        for name, text in overrides.items():
            where = ("--set", 0, 0)
            if name.startswith("noise."):
                noise_raw[name[6:]] = _number_or_text(text)
            elif name in ("tick_hz", "time_limit"):
                value = self.quantity(text, empty, where, name, "frequency" if name == "tick_hz" else "time")
                if value is not None:
                    values[name] = value
            elif name == "sensor_model":
                self._sensor_model(text, where, values)
            elif name == "robot":
                self._robot(text, where, values)
            elif name == "seed":
                try:
                    values["seed"] = int(text)
                except ValueError:
                    self.problem(f"seed must be a whole number, got '{text}'", where, name)
            elif name in params:
                old = params[name]
                new = self.parameter_value(text, where, name)
                if isinstance(old, Quantity) and isinstance(new, Quantity):
                    error = check_kind(new, old.kind)
                    if error:
                        self.problem(f"--set {name}: {error}", where, name)
                        continue
                    new = Quantity(new.value, new.kind or old.kind)
                params[name] = new
            else:
                self.problem(f"--set {name}: no such parameter", where, name,
                             did_you_mean(name, [*params, "tick_hz", "time_limit", "seed", "sensor_model", "robot", "noise.range_sd",
                                                 "noise.wheel", "noise.odometry"]))
        try:
            values["noise"] = NoiseConfig.model_validate(noise_raw)
        except ValidationError as exc:
            self.problems.extend(problems_from(exc, data.get("noise", {}), file, NoiseConfig, "noise."))
            values["noise"] = NoiseConfig()
        return values

    def _sensor_model(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        if value in SENSOR_MODELS:
            values["sensor_model"] = value
        else:
            self.problem(f"sensor_model must be one of {', '.join(SENSOR_MODELS)}, got {value!r}", where,
                         "sensor_model", "raw: a real Thymio's integer readings through its calibration table")

    def _robot(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        if value in ROBOTS:
            values["robot"] = value
        else:
            self.problem(f"robot must be one of {', '.join(ROBOTS)}, got {value!r}", where, "robot",
                         did_you_mean(str(value), ROBOTS))

    def _backend(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        """``backend: NAME`` or ``backend: {name: NAME, OPTION: VALUE, ...}``; the backend checks its options."""
        if isinstance(value, str):
            values["backend"] = value
        elif isinstance(value, dict) and isinstance(value.get("name"), str):
            values["backend"] = value["name"]
            values["backend_options"] = {k: v for k, v in value.items() if k != "name"}
        else:
            self.problem("backend must be a name or a mapping with 'name' and the backend's options", where,
                         "backend", "e.g. backend: {name: aseba, device: /dev/ttyACM0}")

    def _subtrees(self, data: MarkedDict, file: str) -> None:
        raw = data.get("subtrees") or MarkedDict()
        if not isinstance(raw, dict):
            self.problem("subtrees: must be a mapping of name: {parameters, tree}",
                         self.where_value(data, "subtrees", file), "subtrees")
            return
        for name, body in raw.items():
            where = self.where_key(raw, name, file)
            if not isinstance(name, str) or not name.isidentifier():
                self.problem(f"subtree name {name!r} must be a plain identifier", where, "subtrees")
                continue
            if name in self.registry:
                self.problem(f"subtree name '{name}' is already a behaviour, composite or decorator",
                             where, f"subtrees.{name}", "choose another name")
                continue
            if name in self.subtrees:
                first = self.subtrees[name].where
                self.problem(f"subtree '{name}' is defined twice (first at {first[0]}:{first[1]})",
                             where, f"subtrees.{name}")
                continue
            if not isinstance(body, MarkedDict) or "tree" not in body:
                self.problem(f"subtree '{name}' needs a 'tree:' (and optional 'parameters:')",
                             where, f"subtrees.{name}")
                continue
            self.check_keys(body, ("parameters", "tree", "description"), file, f"subtrees.{name}", "a subtree")
            self.subtrees[name] = _Subtree(name, body, (file, *body.mark))

    def _maze(self, data: MarkedDict, path: Path, override: str | Path | None) -> tuple[Maze | None, Path | None]:
        file = str(path)
        if override is not None:
            ref, base, where = str(override), None, ("--maze", 0, 0)
        elif "maze" in data:
            ref, base, where = data["maze"], path.parent, self.where_value(data, "maze", file)
        else:
            self.problem("missing required key 'maze'", (file, *data.mark), "",
                         "name a maze (e.g. two_parts_maze) or give a path relative to this file")
            return None, None
        if not isinstance(ref, str):
            self.problem("maze: must be a maze name or a file path", where, "maze")
            return None, None
        try:
            maze_file = resolve_maze(ref, base)
            return load_maze(maze_file), maze_file
        except UserError as exc:
            for p in exc.problems:
                self.problems.append(p if p.line else Problem(p.message, *where, "maze", p.hint))
            return None, None

    def _start(self, data: MarkedDict, file: str, maze: Maze | None, override: str | None,
               robot: str) -> Pose | None:
        if override is not None:
            where: Where = ("--start", 0, 0)
            raw: Any = override
        elif "start" in data:
            where, raw = self.where_value(data, "start", file), data["start"]
        else:
            self.problem("missing required key 'start'", (file, *data.mark), "",
                         "a named spawn of the maze (e.g. part1) or [x, y, yaw]")
            return None
        pose = self.pose(raw, where, "start", _Scope({}), maze)
        if pose is not None and maze is not None:
            problem = placement_problem(maze, robot_model(robot), pose)
            if problem:
                self.problem(f"impossible start pose: {problem}", where, "start",
                             "pick a free pose inside the maze"
                             + (f", e.g. one of its spawns: {', '.join(maze.spawns)}" if maze.spawns else ""))
                return None
        return pose

    def pose(self, raw: Any, where: Where, path: str, scope: _Scope, maze: Maze | None) -> Pose | None:
        """A pose from ``[x, y, yaw]``, ``"x,y,yaw"`` or the name of a spawn of the maze."""
        if isinstance(raw, str) and "," not in raw:
            if maze is None:
                return None
            if raw in maze.spawns:
                return maze.spawns[raw].pose()
            self.problem(f"maze '{maze.name}' has no spawn named '{raw}'", where, path,
                         did_you_mean(raw, maze.spawns) if maze.spawns else "give [x, y, yaw] instead")
            return None
        if isinstance(raw, str):
            try:
                return Pose(*parse_pose(raw))
            except UnitError as exc:
                self.problem(str(exc), where, path)
                return None
        if not isinstance(raw, list) or len(raw) != 3:
            spawns = f", or one of the maze's spawns: {', '.join(maze.spawns)}" if maze and maze.spawns else ""
            self.problem("a pose is [x, y, yaw] or the name of a maze spawn", where, path,
                         "e.g. [0.5, 0.3, pi/2] or [50cm, 30cm, 90deg]" + spawns)
            return None
        parts = [self.quantity(v, scope, self.where_item(raw, i, where), path, kind)
                 for i, (v, kind) in enumerate(zip(raw, ("length", "length", "angle")))]
        if any(p is None for p in parts):
            return None
        return Pose(*parts)  # type: ignore[arg-type]

    # -------------------------------------------------------------- nodes
    def node(self, value: Any, where: Where, path: str, scope: _Scope, depth: int,
             subtree_stack: tuple[str, ...]) -> NodePlan | None:
        """One tree node: ``{Type: body}``, or a bare ``Type`` string for a node without parameters."""
        file = where[0]
        self.node_count += 1
        if self.node_count > MAX_NODES:
            if self.node_count == MAX_NODES + 1:
                self.problem(f"the tree expands to more than {MAX_NODES} nodes", where, path,
                             "subtrees that use other subtrees several times multiply; simplify the tree")
            return None
        if depth > MAX_DEPTH:
            if where not in self.too_deep:      # once per place, not once per subtree expansion
                self.too_deep.add(where)
                self.problem(f"the tree is nested deeper than {MAX_DEPTH} levels", where, path)
            return None
        if isinstance(value, str):
            kind, body, body_where = value, None, where
        elif isinstance(value, MarkedDict) and len(value) == 1:
            kind = next(iter(value))
            body, body_where = value[kind], self.where_value(value, kind, file)
            where = self.where_key(value, kind, file)
        else:
            keys = f" (found keys: {', '.join(map(str, value))})" if isinstance(value, dict) and value else ""
            self.problem(f"a node is a mapping with exactly one key: a behaviour, composite, decorator "
                         f"or subtree name{keys}", where, path,
                         "e.g. '- MoveUntilWall: {distance: 5cm}' or '- sequence: [...]'")
            return None
        if not isinstance(kind, str):
            self.problem(f"a node type must be a name, got {type_name(kind)}", where, path)
            return None
        node_path = f"{path}.{kind}" if path else kind
        if kind in self.registry:
            cls = self.registry[kind]
            if issubclass(cls, ControlNode):
                return self._control(cls, body, where, body_where, node_path, scope, depth, subtree_stack)
            return self._behaviour(kind, body, where, body_where, node_path, scope)
        if kind in self.subtrees:
            return self._use_subtree(kind, body, where, body_where, node_path, scope, depth, subtree_stack)
        self.problem(f"unknown node type '{kind}'", where, node_path,
                     did_you_mean(kind, [*self.registry, *self.subtrees]))
        return None

    def _name(self, body: Any, default: str, file: str, path: str) -> str:
        if isinstance(body, MarkedDict) and "name" in body:
            name = body["name"]
            if isinstance(name, str) and name and "/" not in name:
                return name
            self.problem("name must be a non-empty string without '/'", self.where_value(body, "name", file), path)
        return default

    def _children(self, raw: Any, where: Where, path: str, scope: _Scope, depth: int,
                  stack: tuple[str, ...]) -> list[NodePlan]:
        file = where[0]
        if not isinstance(raw, list) or not raw:
            self.problem("children must be a non-empty list of nodes", where, path,
                         "e.g. children: [{MoveUntilWall: {distance: 5cm}}, {TurnAngle: {angle: 90deg}}]")
            return []
        children = []
        for i, item in enumerate(raw):
            child = self.node(item, self.where_value(raw, i, file), f"{path}[{i}]", scope, depth + 1, stack)
            if child is not None:
                children.append(child)
        seen: dict[str, int] = {}
        for child in children:           # unique names among siblings keep node paths unambiguous
            count = seen.get(child.name, 0) + 1
            seen[child.name] = count
            if count > 1:
                child.name = f"{child.name}#{count}"
        return children

    def _control(self, cls: type[ControlNode], body: Any, where: Where, body_where: Where, path: str,
                 scope: _Scope, depth: int, stack: tuple[str, ...]) -> NodePlan | None:
        """A composite (``children``) or decorator (``do`` and its other node keys), with its parameters."""
        file, kind = where[0], cls.yaml_name
        composite = cls.category == "composite"
        long_form = isinstance(body, MarkedDict) and ("children" in body if composite else "do" in body)
        if composite and isinstance(body, MarkedDict):
            long_form = True
        elif not composite and not long_form and not cls.short_form:
            self.problem(f"{kind} needs a mapping with {', '.join(cls.keys())}", body_where, path, cls.example)
            return None
        if long_form:
            self.check_keys(body, ("name", *cls.keys()), file, path, f"a {kind}")
        fields = cls.Params.model_fields
        params, _ = self._params(kind, cls.Params, body if long_form else MarkedDict(),
                                 [k for k in body if k in fields] if long_form else [], where, path, scope,
                                 allow_refs=False, missing_hint=cls.example)
        if composite:
            raw_children = body.get("children") if long_form else body
            children_where = self.where_value(body, "children", file) if long_form and "children" in body \
                else body_where
            children = self._children(raw_children, children_where, path, scope, depth, stack)
        else:
            child = self.node(body["do"], self.where_value(body, "do", file), f"{path}.do", scope, depth + 1, stack) \
                if long_form else self.node(body, body_where, f"{path}.do", scope, depth + 1, stack)
            children = [child] if child is not None else []
            for key in cls.node_keys:
                if long_form and key in body:
                    extra = self.node(body[key], self.where_value(body, key, file), f"{path}.{key}", scope,
                                      depth + 1, stack)
                    if extra is not None:
                        children.append(extra)
                elif key in cls.required_nodes:
                    self.problem(f"{kind} needs a {key}", body_where, path, cls.example)
                    return None
            for first, second in cls.exclusive:
                if long_form and first in body and second in body:
                    self.problem(f"{kind} takes either {first} or {second}, not both", body_where, path)
            if child is None:
                return None
        if params is None:
            return None
        return NodePlan(kind, self._name(body, kind, file, path), path, params=params,
                        options=params.model_dump(), children=children, where=where)

    def _behaviour(self, kind: str, body: Any, where: Where, body_where: Where, path: str,
                   scope: _Scope) -> NodePlan | None:
        file = where[0]
        if body is None:
            body = MarkedDict()
        if not isinstance(body, MarkedDict):
            self.problem(f"{kind} takes a mapping of parameters, got {type_name(body)}", body_where, path,
                         f"e.g. '{kind}: {{}}'; see 'thymio-bt behaviours {kind}'")
            return None
        params, refs = self._params(kind, self.registry[kind].Params, body, [k for k in body if k != "name"],
                                    where, path, scope, allow_refs=True)
        if params is None:
            return None
        return NodePlan("behaviour", self._name(body, kind, file, path), path, behaviour=kind,
                        params=params, blackboard_refs=refs, where=where)

    def _params(self, kind: str, model: type[BaseModel], body: MarkedDict, keys: list[Any], where: Where,
                path: str, scope: _Scope, allow_refs: bool, missing_hint: str = "") -> tuple[Any, dict[str, str]]:
        """A node's parameter model from ``keys`` of ``body`` (units, $parameters, bb: references when
        ``allow_refs``), with every problem reported at its place; (None, refs) when there is one."""
        file = where[0]
        fields = model.model_fields
        values: dict[str, Any] = {}
        refs: dict[str, str] = {}
        unknown = False             # a misspelt key: the field it meant is 'missing' too, say it once
        before = len(self.problems)
        for key in keys:
            raw = body[key]
            vwhere = self.where_value(body, key, file)
            if key not in fields:
                self.problem(f"{kind} has no parameter '{key}'", self.where_key(body, key, file), f"{path}.{key}",
                             did_you_mean(str(key), fields))
                unknown = True
                continue
            if allow_refs and isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier():
                looked = scope.values.get(raw[1:]) if raw[1:] in scope.names() else None
                if looked is None and raw[1:] in scope.names():
                    looked = scope.get(raw[1:])
                if isinstance(looked, str) and looked.startswith("bb:"):
                    raw = looked
            if allow_refs and isinstance(raw, str) and raw.startswith("bb:"):
                refs[key] = raw[3:].strip()
                if not refs[key]:
                    self.problem("bb: needs a blackboard key", vwhere, f"{path}.{key}",
                                 "e.g. bb:turn_angle (the key ChooseTurn writes)")
                continue
            value = self.field_value(fields[key], raw, scope, vwhere, f"{path}.{key}")
            if value is not _INVALID:
                values[key] = value
        failed = {key for key in keys if key not in values and key not in refs}     # already reported
        try:
            params = model.model_validate(values)
        except ValidationError as exc:
            # the other values are still checked, so that every problem of the node is reported at once
            errors = [e for e in exc.errors(include_url=False)
                      if not (e["type"] == "missing" and e["loc"] and (e["loc"][0] in refs or e["loc"][0] in failed
                                                                       or unknown))]
            if errors:
                for err in errors:
                    key = err["loc"][0] if err["loc"] else None
                    vwhere = self.where_value(body, key, file) if key in body else where
                    message = err["msg"].removeprefix("Value error, ")
                    hint = str((err.get("ctx") or {}).get("hint", ""))
                    if not hint and err["type"] in ("bool_parsing", "bool_type"):
                        hint = "write true or false"
                    elif not hint and key in fields:
                        hint = _range_hint(fields[key])
                    if err["type"] == "missing":
                        message = f"{kind} needs '{key}'"
                        hint = missing_hint or fields[key].description or ""
                    self.problem(message, vwhere, f"{path}.{key}" if key else path, hint)
                return None, refs
            params = model.model_construct(**{**{k: None for k in refs}, **values})
        if len(self.problems) > before:
            return None, refs
        return params, refs

    def _use_subtree(self, kind: str, body: Any, where: Where, body_where: Where, path: str,
                     scope: _Scope, depth: int, stack: tuple[str, ...]) -> NodePlan | None:
        file = where[0]
        if kind in stack:
            self.problem(f"subtree '{kind}' uses itself ({' -> '.join([*stack, kind])})", where, path,
                         "a subtree may not contain itself; use repeat: to loop")
            return None
        sub = self.subtrees[kind]
        sfile = sub.where[0]
        declared = sub.body.get("parameters") or MarkedDict()
        if not isinstance(declared, MarkedDict):
            self.problem(f"subtree '{kind}': parameters must be a mapping of name: default",
                         self.where_value(sub.body, "parameters", sfile), f"subtrees.{kind}")
            return None
        values: dict[str, Any] = {}
        for name, raw in declared.items():
            values[name] = self._argument(raw, self.root_scope, self.where_value(declared, name, sfile),
                                          f"subtrees.{kind}.parameters.{name}", None)
        if body is not None and not isinstance(body, MarkedDict):
            self.problem(f"subtree '{kind}' takes a mapping of parameters", body_where, path)
            return None
        for name, raw in (body or {}).items():
            if name == "name":
                continue
            if name not in declared:
                self.problem(f"subtree '{kind}' has no parameter '{name}'", self.where_key(body, name, file),
                             f"{path}.{name}", did_you_mean(str(name), declared) if declared else
                             f"subtree '{kind}' declares no parameters")
                continue
            old = values.get(name)
            values[name] = self._argument(raw, scope, self.where_value(body, name, file), f"{path}.{name}",
                                          old.kind if isinstance(old, Quantity) else None)
        tree = self.node(sub.body["tree"], self.where_value(sub.body, "tree", sfile), path,
                         _Scope(values, self.root_scope), depth + 1, (*stack, kind))
        if tree is not None:
            tree.name = self._name(body, kind, file, path)
        return tree

    def _argument(self, raw: Any, scope: _Scope, where: Where, path: str, kind: str | None) -> Any:
        """A subtree argument: a quantity when it is numeric (in the caller's scope), else as written."""
        if isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier():
            try:
                return scope.get(raw[1:])
            except KeyError:
                self.problem(f"unknown parameter '{raw}'", where, path, _parameter_hint(raw[1:], scope))
                return None
        if isinstance(raw, (int, float)) and not isinstance(raw, bool) or (
                isinstance(raw, str) and not raw.startswith("bb:") and _looks_numeric(raw)):
            value = self.quantity(raw, scope, where, path, kind)
            return None if value is None else Quantity(value, kind or parse_value_kind(raw))
        return raw

    def field_value(self, field: Any, raw: Any, scope: _Scope, where: Where, path: str) -> Any:
        """Convert one YAML value for a parameter field: $references, then by the field's type."""
        annotation = field.annotation
        if isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier() and not _is_number(annotation):
            try:
                value = scope.get(raw[1:])
            except KeyError:
                self.problem(f"unknown parameter '{raw}'", where, path, _parameter_hint(raw[1:], scope))
                return _INVALID
            if isinstance(value, Quantity):
                return value.value
            if not isinstance(value, (str, list)):
                return value
            raw = value            # a text or list parameter (e.g. a spawn name): convert it like a literal
        return self.convert(annotation, field_metadata(field), raw, scope, where, path)

    def convert(self, annotation: Any, extra: list[Any], raw: Any, scope: _Scope, where: Where, path: str) -> Any:
        """A YAML value as the type ``annotation`` wants it: numbers through the unit parser (in the
        type's unit), tuples and lists element by element, spawn names for pose types; anything else
        as written, for pydantic to check. The types (thymio_bt.fields) say everything: a new
        parameter shape built from them needs no change here."""
        meta = metadata(annotation, extra)
        base = _strip_optional(annotation)
        base = typing.get_args(base)[0] if typing.get_origin(base) is typing.Annotated else base
        if raw is None:
            return raw             # an optional value left empty: pydantic says whether that is allowed
        if base in (float, int):
            unit = next((m for m in meta if isinstance(m, Unit)), None)
            value = self.quantity(raw, scope, where, path, unit.kind if unit else None)
            return _INVALID if value is None else value
        origin, args = typing.get_origin(base), typing.get_args(base)
        if origin is tuple:
            if isinstance(raw, str) and "," not in raw and any(isinstance(m, SpawnName) for m in meta):
                if self.maze is None:
                    return raw
                pose = self.pose(raw, where, path, scope, self.maze)
                return _INVALID if pose is None else (pose.x, pose.y, pose.yaw)
            if isinstance(raw, str):
                raw = raw.split(",")
            if isinstance(raw, list) and (len(args) == len(raw) or (len(args) == 2 and args[1] is Ellipsis)):
                kinds = [args[0]] * len(raw) if args[1:] == (Ellipsis,) else list(args)
                out = [self.convert(kind, [], item, scope, where, path) for kind, item in zip(kinds, raw)]
                return _INVALID if any(v is _INVALID for v in out) else tuple(out)
        if origin is list and isinstance(raw, list) and args:
            out = [self.convert(args[0], [], item, scope, self.where_item(raw, i, where), f"{path}[{i}]")
                   for i, item in enumerate(raw)]
            return _INVALID if any(v is _INVALID for v in out) else out
        return raw


_INVALID = object()

def _file_suggestion(missing: Path) -> str:
    """'; did you mean 'maze_legs.yaml'?' when a YAML file of a close name sits beside a missing one."""
    try:
        names = [p.name for p in missing.parent.glob("*.yaml")] if missing.parent.is_dir() else []
    except OSError:
        return ""
    return "; " + did_you_mean(missing.name, names) if names else ""


def _parameter_hint(name: str, scope: _Scope) -> str:
    names = scope.names()
    if not names:
        return "no parameters are defined here: declare it under 'parameters:'"
    return did_you_mean(name, names)


def _strip_optional(annotation: Any) -> Any:
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    if typing.get_origin(annotation) in (typing.Union, types.UnionType) and len(args) == 1:
        return args[0]
    return annotation


def _is_number(annotation: Any) -> bool:
    return _strip_optional(annotation) in (float, int)


def _is_number_text(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _looks_numeric(text: str) -> bool:
    try:
        parse_value(text, lambda name: Quantity(1.0))
        return True
    except UnitError:
        return False


def parse_value_kind(text: str) -> str | None:
    try:
        return parse_value(text, lambda name: Quantity(1.0)).kind
    except UnitError:
        return None


def _number_or_text(text: str) -> Any:
    return float(text) if _is_number_text(text) else text


def _range_hint(field: Any) -> str:
    bounds = []
    for meta in field.metadata:
        for attr, sym in (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<")):
            value = getattr(meta, attr, None)
            if value is not None:
                bounds.append(f"{sym} {value:g}" if isinstance(value, (int, float)) else f"{sym} {value}")
    unit = unit_of(field)
    return f"allowed: {' and '.join(bounds)}{(' ' + unit) if unit else ''}" if bounds else (field.description or "")


def load_mission(path: str | Path, overrides: Mapping[str, str] | None = None,
                 maze: str | Path | None = None, start: str | None = None,
                 registry: Registry | None = None) -> Mission:
    """Load and validate a mission file; raise :class:`UserError` listing every problem."""
    return MissionLoader(registry).load(path, overrides, maze, start)
