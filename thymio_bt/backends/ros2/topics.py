"""Where a ROS 2 Thymio's data is: topic and service names, message kinds and rates (a topic map).

The default is the course's Gazebo classic layout (docs/sources.md, "Robot geometry and sensors"):
``/cmd_vel`` Twist in, ``/odom`` Odometry at 50 Hz (world pose), one single-ray LaserScan per proximity sensor on
``/thymio_<prefix>_sensor`` at 10 Hz, Gazebo's ``/spawn_entity`` and ``/delete_entity`` services and
``/clock``. Another layout is a YAML file of the keys to change, e.g. for a driver publishing Range::

    # my_thymio.yaml                     (thymio-bt run M --backend ros2 --backend-opt topics=my_thymio.yaml)
    sensor_type: Range
    sensors: {front_center: /proximity/center, rear_left: /proximity/rear_left}
    spawn: ""                            # no spawn service: the operator places the robot

Example::

    >>> COURSE_TOPICS.sensors["front_center"]
    '/thymio_front_center_proximity_sensor'
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.robot.interface import SENSOR_NAMES

#: the URDF prefix of each sensor (``<prefix>_link`` is its frame, ``/thymio_<prefix>_sensor`` its topic)
PREFIXES: dict[str, str] = {name: f"{name}_proximity" for name in SENSOR_NAMES}


class TopicMap(BaseModel):
    """Topic and service names of one ROS 2 Thymio layout; empty names mean "not offered"."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    cmd_vel: str = Field("/cmd_vel", description="geometry_msgs/Twist the robot obeys (held until changed)")
    odom: str = Field("/odom", description="nav_msgs/Odometry of base_footprint in the world frame")
    odom_rate: float = Field(50.0, gt=0, le=1000, description="how often odom is published (Hz)")
    clock: str = Field("/clock", description="rosgraph_msgs/Clock; simulated time when someone publishes it")
    sensor_type: Literal["LaserScan", "Range"] = Field(
        "LaserScan", description="the proximity messages: single-ray LaserScan (Gazebo) or Range (drivers)"
    )
    sensor_rate: float = Field(10.0, gt=0, le=1000, description="how often each proximity sensor publishes (Hz)")
    sensors: dict[str, str] = Field(
        default_factory=lambda: {name: f"/thymio_{prefix}_sensor" for name, prefix in PREFIXES.items()},
        description="topic of each proximity sensor, by thymio-bt's sensor name",
    )
    spawn: str = Field("/spawn_entity", description="gazebo_msgs/srv/SpawnEntity service, or empty")
    delete: str = Field("/delete_entity", description="gazebo_msgs/srv/DeleteEntity service, or empty")
    robot_description: str = Field(
        "/robot_description", description="std_msgs/String with the robot's URDF, sent when spawning"
    )

    @field_validator("sensors")
    @classmethod
    def _known_sensors(cls, sensors: dict[str, str]) -> dict[str, str]:
        for name in sensors:
            if name not in SENSOR_NAMES:
                raise ValueError(f"no sensor named '{name}' ({did_you_mean(name, SENSOR_NAMES)})")
        return sensors


COURSE_TOPICS = TopicMap()


def load_topics(path: str | Path) -> TopicMap:
    """A topic map from a YAML file: the course's layout with the file's keys replacing its own.
    ``sensors`` replaces the whole table (a robot may have fewer sensors)."""
    from thymio_bt.inputs.validation import problems_from
    from thymio_bt.inputs.yamlio import load_yaml

    data = load_yaml(path, "include")
    if not isinstance(data, dict):
        raise UserError(
            Problem(
                "a topic map is a mapping of names, e.g. 'odom: /odom'",
                str(path),
                1,
                1,
                hint="keys: " + ", ".join(TopicMap.model_fields),
            )
        )
    try:
        return TopicMap.model_validate(dict(data))
    except ValidationError as exc:
        raise UserError(problems_from(exc, data, str(path), TopicMap, at=(1, 1))) from None
