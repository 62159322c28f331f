"""The assemble pass: one mission file and what it pulls in, put together and checked.

From the YAML read with marks, it loads plugins, includes (recursively), parameters, subtrees and the
settings (tick rate, time limit, seed, noise, sensor model, robot, backend, and ``--set``
overrides), then the maze and the start pose. What comes out, an :class:`Assembly`, is what the
planning pass needs to turn the ``tree:`` into a :class:`~thymio_bt.mission.plan.NodePlan`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from thymio_bt.robot.noise import NoiseConfig
from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.units import Quantity, check_kind
from thymio_bt.inputs.validation import problems_from, validate
from thymio_bt.inputs.yamlio import MarkedDict, load_yaml
from thymio_bt.maze import Maze, load_maze, resolve_maze
from thymio_bt.mission.checker import Checker, Scope, Where
from thymio_bt.mission.expect import Expect
from thymio_bt.mission.registry import Registry, default_registry
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import ROBOTS, robot_model
from thymio_bt.robot.placement import placement_problem
from thymio_bt.robot.profile import is_profile_path

#: the settings that are numbers: their kind and range, however they are given
SETTING_RANGES = {"tick_hz": ("frequency", 1.0, 100.0), "time_limit": ("time", 0.1, 36000.0)}
MAX_SEED = 2**63 - 1

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
SENSOR_MODELS = ("metres", "raw", "cone")
#: a robot model's sensor model as the simulator calls it ("rays": the course's exact rays, in metres)
_SIM_SENSOR_MODEL = {"rays": "metres", "raw": "raw", "cone": "cone"}
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


class Assembler(Checker):
    """Runs the assemble pass over one mission file."""

    def __init__(self, registry: Registry | None = None, run_plugins: bool = True) -> None:
        super().__init__([])
        self.registry = (registry or default_registry()).copy()
        self.run_plugins = run_plugins
        self.subtrees: dict[str, Subtree] = {}
        self.included_parameters: list[tuple[MarkedDict, str]] = []
        self.included: set[Path] = set()

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
            raise UserError(
                Problem(
                    "a mission file must be a mapping with at least 'maze:', 'start:' and 'tree:'",
                    file,
                    *getattr(data, "mark", (1, 1)),
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
        start = self._start(data, file, maze, start_override, settings.get("robot", "course"))
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
        )

    def _plugins(self, data: MarkedDict, path: Path) -> None:
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
            target = (path.parent / ref).resolve()
            shown = Path(os.path.normpath(path.parent / ref))  # as the user would write it ...
            if shown.resolve() != target:
                shown = target  # ... unless symbolic links disagree
            if target in stack:
                cycle = " -> ".join(p.name for p in [*stack[stack.index(target) :], target])
                self.problem(
                    f"include cycle: {cycle}",
                    where,
                    f"include[{i}]",
                    "a file may not include itself, directly or through others",
                )
                continue
            if target in self.included:
                continue  # included twice (e.g. by two included files): once is enough
            self.included.add(target)
            if not target.exists():
                self.problem(
                    f"included file not found: {shown}",
                    where,
                    f"include[{i}]",
                    "include paths are relative to the including file" + _file_suggestion(shown),
                )
                continue
            try:
                included = load_yaml(shown, "include")
            except UserError as exc:
                for p in exc.problems:
                    self.problems.append(p if p.line else Problem(p.message, *where, f"include[{i}]", p.hint))
                continue
            if not isinstance(included, MarkedDict):
                self.problem(
                    "an included file must be a mapping with 'subtrees:'",
                    (str(shown), *getattr(included, "mark", (1, 1))),
                    "",
                    "e.g. missions/lib/maze_legs.yaml",
                )
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

    def _settings(
        self, data: MarkedDict, file: str, params: dict[str, Any], overrides: Mapping[str, str]
    ) -> dict[str, Any]:
        values: dict[str, Any] = {"tick_hz": 10.0, "time_limit": 300.0, "seed": 0}
        noise_raw: dict[str, Any] = {}
        for key in ("tick_hz", "time_limit", "seed"):
            if key in data:
                self._setting(key, data[key], self.where_value(data, key, file), values)
        if "sensor_model" in data:
            self._sensor_model(data["sensor_model"], self.where_value(data, "sensor_model", file), values)
        if "robot" in data:
            self._robot(data["robot"], self.where_value(data, "robot", file), values)
        if "backend" in data:
            self._backend(data["backend"], self.where_value(data, "backend", file), values)
        if "expect" in data:
            try:
                values["expect"] = validate(Expect, data["expect"], file, "expect.")
            except UserError as exc:
                self.problems.extend(exc.problems)
        if "noise" in data:
            noise = data["noise"]
            if isinstance(noise, MarkedDict):
                noise_raw = dict(noise)
            else:
                self.problem(
                    "noise: must be a mapping (range_sd, wheel, odometry)",
                    self.where_value(data, "noise", file),
                    "noise",
                )
        for name, text in overrides.items():
            where = ("--set", 0, 0)
            if name.startswith("noise."):
                noise_raw[name[6:]] = _number_or_text(text)
            elif name in ("tick_hz", "time_limit", "seed"):
                self._setting(name, _whole_or_text(text) if name == "seed" else text, where, values)
            elif name == "sensor_model":
                self._sensor_model(text, where, values)
            elif name == "robot":
                self._robot(text, where, values)
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
                self.problem(
                    f"--set {name}: no such parameter",
                    where,
                    name,
                    did_you_mean(
                        name,
                        [
                            *params,
                            "tick_hz",
                            "time_limit",
                            "seed",
                            "sensor_model",
                            "robot",
                            "noise.range_sd",
                            "noise.wheel",
                            "noise.odometry",
                        ],
                    ),
                )
        motor_noise = robot_model(values.get("robot", "course")).motor_noise
        if motor_noise and "wheel" not in noise_raw:  # the robot's own (Enki's cannot be switched off)
            noise_raw["wheel"] = motor_noise
        try:
            values["noise"] = NoiseConfig.model_validate(noise_raw)
        except ValidationError as exc:
            self.problems.extend(problems_from(exc, data.get("noise", {}), file, NoiseConfig, "noise."))
            values["noise"] = NoiseConfig()
        if "sensor_model" not in values:  # the robot's own: the course's rays, Enki's cones, a real robot's readings
            values["sensor_model"] = _SIM_SENSOR_MODEL[robot_model(values.get("robot", "course")).sensor_model]
        return values

    def _setting(self, key: str, raw: Any, where: Where, values: dict[str, Any]) -> None:
        """``tick_hz``, ``time_limit`` or ``seed``, from the file or ``--set``: the same checks either way."""
        if key == "seed":
            if isinstance(raw, bool) or not isinstance(raw, int) or not 0 <= raw <= MAX_SEED:
                self.problem(
                    f"seed must be a whole number >= 0 (at most {MAX_SEED}), got {raw!r}",
                    where,
                    "seed",
                    "e.g. seed: 42",
                )
            else:
                values["seed"] = raw
            return
        kind, lo, hi = SETTING_RANGES[key]
        value = self.quantity(raw, Scope({}), where, key, kind)
        if value is not None and not lo <= value <= hi:
            self.problem(f"{key} must be between {lo:g} and {hi:g}, got {value:g}", where, key)
        elif value is not None:
            values[key] = value

    def _sensor_model(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        if value == "rays":  # the robot models' name for the course's exact rays
            value = "metres"
        if value in SENSOR_MODELS:
            values["sensor_model"] = value
        else:
            self.problem(
                f"sensor_model must be one of {', '.join(SENSOR_MODELS)}, got {value!r}",
                where,
                "sensor_model",
                "raw: a real Thymio's integer readings through its calibration table; cone: Enki's three-ray cones",
            )

    def _robot(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        if value in ROBOTS:
            values["robot"] = value
        elif isinstance(value, str) and is_profile_path(value):
            # a profile file (thymio-bt calibrate): relative to the mission's folder, or to here for --robot
            path = (
                Path(value)
                if Path(value).is_absolute() or not Path(where[0]).is_file()
                else Path(where[0]).parent / value
            )
            try:
                robot_model(str(path.resolve()))
            except UserError as exc:
                self.problems.extend(p if p.line else Problem(p.message, *where, "robot", p.hint) for p in exc.problems)
                return
            values["robot"] = str(path.resolve())
        else:
            self.problem(
                f"robot must be one of {', '.join(ROBOTS)} or a profile file (.yaml), got {value!r}",
                where,
                "robot",
                did_you_mean(str(value), ROBOTS),
            )

    def _backend(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        """``backend: NAME`` or ``backend: {name: NAME, OPTION: VALUE, ...}``; the backend checks its options."""
        if isinstance(value, str):
            values["backend"] = value
        elif isinstance(value, dict) and isinstance(value.get("name"), str):
            values["backend"] = value["name"]
            values["backend_options"] = {k: v for k, v in value.items() if k != "name"}
        else:
            self.problem(
                "backend must be a name or a mapping with 'name' and the backend's options",
                where,
                "backend",
                "e.g. backend: {name: aseba, device: /dev/ttyACM0}",
            )

    def _subtrees(self, data: MarkedDict, file: str) -> None:
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
            self.subtrees[name] = Subtree(name, body, (file, *body.mark))

    def _maze(self, data: MarkedDict, path: Path, override: str | Path | None) -> tuple[Maze | None, Path | None]:
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
            for p in exc.problems:
                self.problems.append(p if p.line else Problem(p.message, *where, "maze", p.hint))
            return None, None

    def _start(self, data: MarkedDict, file: str, maze: Maze | None, override: str | None, robot: str) -> Pose | None:
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
        if pose is not None and maze is not None:
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


def _is_number_text(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _whole_or_text(text: str) -> Any:
    try:
        return int(text)
    except ValueError:
        return text


def _number_or_text(text: str) -> Any:
    return float(text) if _is_number_text(text) else text
