"""Robot profile files: a robot model measured by ``thymio-bt calibrate``, usable as ``--robot FILE``.

A profile names a built-in model to start from and the numbers measured on one robot; everything
else (geometry, sensor poses, the simulator's sensor model) comes from the base::

    # my_thymio.yaml, written by: thymio-bt calibrate --backend aseba -o my_thymio.yaml
    base: real
    name: my_thymio
    metres_per_unit: 0.000391          # wheel speed per motor unit (m/s)
    wheel_separation: 0.0928           # m
    calibration:                       # front-centre reading against distance, nearest first
      distances: [0.01, 0.02, 0.03, 0.0933]
      readings: [4279, 4139, 3515, 0]
      floor: 0                         # readings at or below it mean nothing in range (noise)

Example::

    >>> import pathlib, tempfile
    >>> from thymio_bt.robot.model import robot_model
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "my_thymio.yaml"
    >>> _ = path.write_text("{base: real, name: my_thymio, metres_per_unit: 0.000391, wheel_separation: 0.0928}")
    >>> model = robot_model(str(path))          # the real model with the measured numbers
    >>> model.name, model.max_wheel_speed, model.wheel_separation, model.sensor_model
    ('my_thymio', 0.1955, 0.0928, 'raw')
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.sensor_tables import CalibrationTable

#: the suffixes that make a ``--robot`` value a profile file rather than a model's name
PROFILE_SUFFIXES = (".yaml", ".yml")


class TableRows(BaseModel):
    """A profile's calibration table: distances and readings, row by row."""

    model_config = ConfigDict(extra="forbid")

    distances: list[float] = Field(description="metres, increasing")
    readings: list[float] = Field(description="raw prox.horizontal, decreasing, ending at 0")
    floor: float | None = Field(
        None,
        ge=0,
        description="readings at or below this are noise: nothing in range (default: the base model's)",
    )


class Profile(BaseModel):
    """What a profile file holds (see the module docstring)."""

    model_config = ConfigDict(extra="forbid")

    base: str = Field(description="the built-in model it starts from: course, enki or real")
    name: str = Field(description="the profile's name, for reports")
    description: str = ""
    metres_per_unit: float | None = Field(None, gt=0, lt=0.01, description="wheel speed per motor unit (m/s)")
    wheel_separation: float | None = Field(None, gt=0.05, lt=0.15, description="wheel base (m)")
    calibration: TableRows | None = None
    #: what calibrate measured and how (kept for the record; not used by runs)
    measured: dict[str, Any] = Field(default={})


def is_profile_path(name: str) -> bool:
    """Whether ``name`` is a profile file (``.yaml``, ``.yml``) rather than a built-in model's name."""
    return name.lower().endswith(PROFILE_SUFFIXES)


class Base(Protocol):
    """What a profile reads of the built-in model it starts from (a
    :class:`~thymio_bt.robot.model.RobotModel` is one; the models import this module, not the reverse)."""

    @property
    def max_units(self) -> int:
        """Its wheels' fastest target, in Aseba motor units."""
        ...

    @property
    def calibration(self) -> CalibrationTable:
        """Its sensors' table, whose floor a measured table without one keeps."""
        ...


def read_profile(path: str, named: Mapping[str, Base]) -> tuple[str, dict[str, Any]]:
    """The base a profile file names among ``named`` (models by name) and the fields it changes of
    that model; a located :class:`UserError` when the file is missing or wrong. Use
    :func:`thymio_bt.robot.model.robot_model`, which passes the built-in models and makes the model."""
    from thymio_bt.inputs.validation import problems_from
    from thymio_bt.inputs.yamlio import MarkedDict, load_yaml

    data = load_yaml(path, "include")
    if not isinstance(data, dict):
        raise UserError(Problem("a robot profile is a mapping (base, name, metres_per_unit, ...)", str(path), 1, 1))
    marks = data.marks if isinstance(data, MarkedDict) else {}
    problems = []
    if "base" in data and data["base"] not in named:
        problems.append(
            Problem(
                f"'base': no built-in robot model {data['base']!r}",
                str(path),
                *marks.get("base", (1, 1)),
                hint=did_you_mean(str(data["base"]), named),
            )
        )
    try:
        profile = Profile.model_validate(dict(data))
    except ValidationError as exc:
        problems += problems_from(exc, data, str(path), Profile, at=(1, 1))
    if problems:
        raise UserError(problems)
    base = named[profile.base]
    changes: dict[str, Any] = {
        "name": profile.name,
        "description": profile.description
        or f"{profile.name}: {profile.base} with measured numbers ({Path(path).name})",
    }
    if profile.metres_per_unit is not None:
        changes["metres_per_unit"] = profile.metres_per_unit
        changes["max_wheel_speed"] = profile.metres_per_unit * base.max_units
    if profile.wheel_separation is not None:
        changes["wheel_separation"] = profile.wheel_separation
    if profile.calibration is not None:
        try:
            table = profile.calibration
            changes["calibration"] = CalibrationTable(
                tuple(table.distances),
                tuple(table.readings),
                source=str(path),
                floor=base.calibration.floor if table.floor is None else table.floor,
            )
        except ValueError as exc:
            raise UserError(Problem(f"'calibration': {exc}", str(path), *marks.get("calibration", (1, 1)))) from None
    return profile.base, changes


def profile_text(profile: Profile) -> str:
    """A profile as the YAML file :func:`read_profile` reads."""
    import yaml

    data = profile.model_dump(exclude_none=True)
    return "# A robot profile (thymio-bt calibrate); use it with --robot THIS_FILE\n" + yaml.safe_dump(
        data, sort_keys=False
    )
