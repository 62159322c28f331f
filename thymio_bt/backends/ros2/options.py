"""The ``ros2`` backend's settings (``--backend-opt KEY=VALUE`` or a mission's ``backend:`` block).

Reading them needs no ROS: ``thymio-bt backends`` lists them anywhere."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from thymio_bt.backends import BackendOptions, latency_option


class Ros2Options(BackendOptions):
    """The ``ros2`` backend's settings: the topic map, the clock, the latency and the robot's URDF."""

    topics: str = Field("", description="a YAML topic map (default: the course's Gazebo topics and services)")
    timeout: float = Field(
        5.0,
        gt=0,
        le=120,
        description="how long a topic may stay silent, or a service "
        "take to appear or answer, before the run fails (wall s)",
    )
    clock: Literal["auto", "sim", "wall"] = Field(
        "auto",
        description="the run's time: the /clock of a simulator (sim), the wall clock (wall), or sim "
        "when someone publishes /clock (auto)",
    )
    latency: float = latency_option(0.0, " (behaviours stop early by it); measure a real robot's")
    robot_xml: str = Field("", description="URDF/SDF file sent when spawning (default: /robot_description)")
