"""A mission's settings: ``tick_hz``, ``time_limit``, ``seed``, ``sensor_model``, ``robot``,
``backend``, ``expect`` and ``noise``, from the file and then from ``--set NAME=VALUE`` (which also
sets the mission's parameters). Part of the assemble pass (:mod:`thymio_bt.mission.assemble`): the
same checks, and the same messages, whichever way a setting is given.

Example::

    >>> from thymio_bt.mission.loader import load_mission
    >>> mission = load_mission("maze_part1_2", overrides={"tick_hz": "20 Hz", "cruise": "15cm/s"})
    >>> mission.tick_hz, mission.parameters["cruise"], mission.sensor_model
    (20.0, 0.15, 'metres')
    >>> try:
    ...     load_mission("maze_part1_2", overrides={"cruise": "90deg"})
    ... except UserError as exc:
    ...     print(exc)
    --set: cruise: expected a speed (in m/s), got an angle [at cruise] (hint: write a speed: 10cm/s or 0.1 m/s)
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.units import Quantity, check_kind, resolver_from
from thymio_bt.inputs.validation import problems_from, validate
from thymio_bt.inputs.yamlio import MarkedDict
from thymio_bt.mission.parameters import SetValue
from thymio_bt.mission.pass_base import LoaderPass, Scope, Where
from thymio_bt.plan.expect import Expect
from thymio_bt.robot.model import ROBOTS, SIM_SENSOR_MODEL, SIM_SENSOR_MODELS, robot_model
from thymio_bt.robot.noise import NoiseConfig

#: the settings that are numbers: their kind and range, however they are given
SETTING_RANGES = {"tick_hz": ("frequency", 1.0, 100.0), "time_limit": ("time", 0.1, 36000.0)}
MAX_SEED = 2**63 - 1
#: the settings ``--set`` takes besides the mission's parameters
OVERRIDABLE = (
    "tick_hz",
    "time_limit",
    "seed",
    "sensor_model",
    "robot",
    "noise.range_sd",
    "noise.wheel",
    "noise.odometry",
)
_OVERRIDE: Where = ("--set", 0, 0)
#: the override that ``run --robot NAME`` makes: ``--set robot=NAME``, its problems said at ``--robot``
ROBOT_OPTION = "--robot"


class SettingsReader(LoaderPass):
    """Reads a mission's settings, and applies ``--set`` to them and to its parameters."""

    #: whether the robot asked for was refused (said already): checks that need it are skipped, not
    #: made against the course robot
    robot_refused = False

    def _settings(
        self, data: MarkedDict, file: str, params: dict[str, Any], overrides: Mapping[str, str]
    ) -> dict[str, Any]:
        """The settings of the mission ``data`` (defaults for those not given), ``overrides``
        applied; a ``--set`` of a parameter changes ``params``."""
        values: dict[str, Any] = {"tick_hz": 10.0, "time_limit": 300.0, "seed": 0}
        noise_raw = self._file_settings(data, file, values)
        for name, text in overrides.items():
            self._override(name, text, params, values, noise_raw)
        if "expect" in data:  # after --set: its values may name the parameters
            try:
                values["expect"] = validate(Expect, data["expect"], file, "expect.", {"resolve": resolver_from(params)})
            except UserError as exc:
                self.problems.extend(exc.problems)
        self._noise(noise_raw, data, file, values)
        if "sensor_model" not in values:  # the robot's own: the course's rays, Enki's cones, a real robot's readings
            values["sensor_model"] = SIM_SENSOR_MODEL[robot_model(values.get("robot")).sensor_model]
        return values

    def _file_settings(self, data: MarkedDict, file: str, values: dict[str, Any]) -> dict[str, Any]:
        """The settings written in the mission file, into ``values``; the ``noise:`` mapping is
        returned as written, for ``--set noise.X`` to change before it is checked."""
        for key in ("tick_hz", "time_limit", "seed"):
            if key in data:
                self._setting(key, data[key], self.where_value(data, key, file), values)
        if "sensor_model" in data:
            self._sensor_model(data["sensor_model"], self.where_value(data, "sensor_model", file), values)
        if "robot" in data:
            self._robot(data["robot"], self.where_value(data, "robot", file), values)
        if "backend" in data:
            self._backend(data["backend"], self.where_value(data, "backend", file), values)
        if "noise" not in data:
            return {}
        if isinstance(data["noise"], MarkedDict):
            return dict(data["noise"])
        self.problem(
            "noise: must be a mapping (range_sd, wheel, odometry)",
            self.where_value(data, "noise", file),
            "noise",
        )
        return {}

    def _override(
        self, name: str, text: str, params: dict[str, Any], values: dict[str, Any], noise_raw: dict[str, Any]
    ) -> None:
        """One ``--set NAME=TEXT``: a setting, a noise level or a mission parameter."""
        if name.startswith("noise."):
            noise_raw[name[6:]] = _number_or_text(text)
        elif name in ("tick_hz", "time_limit", "seed"):
            self._setting(name, _whole_or_text(text) if name == "seed" else text, _OVERRIDE, values)
        elif name == "sensor_model":
            self._sensor_model(text, _OVERRIDE, values)
        elif name in ("robot", ROBOT_OPTION):
            self._robot(text, (ROBOT_OPTION, 0, 0) if name == ROBOT_OPTION else _OVERRIDE, values)
        elif name in params:
            self._override_parameter(name, text, params)
        else:
            self.problem(f"no such parameter '{name}'", _OVERRIDE, name, did_you_mean(name, [*params, *OVERRIDABLE]))

    def _override_parameter(self, name: str, text: str, params: dict[str, Any]) -> None:
        """``--set NAME=TEXT`` of a mission parameter: a quantity keeps the kind of its unit."""
        old = params[name]
        new = self.parameter_value(text, _OVERRIDE, name)
        if isinstance(old, Quantity) and isinstance(new, Quantity):
            error = check_kind(new, old.kind)
            if error:
                self.problem(f"{name}: {error}", _OVERRIDE, name, error.hint)
                return
            new = SetValue(new.value, new.kind or old.kind, name=name, text=text)
        params[name] = new

    def _noise(self, noise_raw: dict[str, Any], data: MarkedDict, file: str, values: dict[str, Any]) -> None:
        """``values["noise"]``: the levels given, with the robot's own motor noise unless a wheel
        noise is given (Enki's cannot be switched off)."""
        motor_noise = robot_model(values.get("robot")).motor_noise
        if motor_noise and "wheel" not in noise_raw:
            noise_raw["wheel"] = motor_noise
        try:
            values["noise"] = NoiseConfig.model_validate(noise_raw)
        except ValidationError as exc:
            written = data.get("noise", {})
            for problem in problems_from(exc, written, file, NoiseConfig, "noise."):
                key = problem.path.removeprefix("noise.")
                if not isinstance(written, dict) or key not in written or written[key] != noise_raw.get(key):
                    problem = Problem(problem.message, *_OVERRIDE, problem.path, problem.hint)  # --set gave it
                self.problems.append(problem)
            values["noise"] = NoiseConfig()

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
            example = (
                "time_limit: 120 (simulated seconds)" if key == "time_limit" else "tick_hz: 10 (the course's rate)"
            )
            self.problem(f"{key} must be between {lo:g} and {hi:g}, got {value:g}", where, key, f"e.g. {example}")
        elif value is not None:
            values[key] = value

    def _sensor_model(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        """``sensor_model``: one of :data:`~thymio_bt.robot.model.SIM_SENSOR_MODELS`, or a robot
        model's name of one (``rays`` is ``metres``: :data:`~thymio_bt.robot.model.SIM_SENSOR_MODEL`)."""
        if isinstance(value, str) and value in SIM_SENSOR_MODEL:  # a list or mapping is no key
            value = SIM_SENSOR_MODEL[value]
        if value in SIM_SENSOR_MODELS:
            values["sensor_model"] = value
        else:
            self.problem(
                f"sensor_model must be one of rays, {', '.join(SIM_SENSOR_MODELS)}, got {value!r}",
                where,
                "sensor_model",
                "rays (or metres): the course's exact rays; raw: a real Thymio's integer readings through its "
                "calibration table; cone: Enki's three-ray cones",
            )

    def _robot(self, value: Any, where: Where, values: dict[str, Any]) -> None:
        """``robot``: a robot model's name, or a profile file (checked by loading it)."""
        from thymio_bt.robot.profile import is_profile_path  # its models load only for a mission naming a robot

        if value in ROBOTS:
            values["robot"] = value
        elif isinstance(value, str) and is_profile_path(value):
            # a profile file (thymio-bt calibrate): relative to the mission's folder, or to here for --robot
            path = (
                Path(value)
                if Path(value).is_absolute() or not Path(where[0]).is_file()
                else Path(where[0]).parent / value
            )
            if not path.exists():
                self.problem(
                    f"robot profile not found: {path}",
                    where,
                    "robot",
                    "make one with 'thymio-bt calibrate -o FILE.yaml', or name a built-in robot: " + ", ".join(ROBOTS),
                )
                self.robot_refused = True
                return
            try:
                robot_model(str(path.resolve()))
            except UserError as exc:
                self.adopt(exc.problems, where, "robot")
                self.robot_refused = True
                return
            values["robot"] = str(path.resolve())
        else:
            self.problem(
                f"robot must be one of {', '.join(ROBOTS)} or a profile file (.yaml), got {value!r}",
                where,
                "robot",
                did_you_mean(str(value), ROBOTS),
            )
            self.robot_refused = True

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


def _is_number_text(text: str) -> bool:
    """Whether ``text`` is a plain number (``float`` reads it)."""
    try:
        float(text)
        return True
    except ValueError:
        return False


def _whole_or_text(text: str) -> Any:
    """``--set seed=42``: the whole number, or the text for the seed's check to refuse."""
    try:
        return int(text)
    except ValueError:
        return text


def _number_or_text(text: str) -> Any:
    """``--set noise.wheel=0.1``: the number, or the text for the noise model to refuse."""
    return float(text) if _is_number_text(text) else text
