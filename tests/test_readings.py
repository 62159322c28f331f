"""Noise-free readings cast when read (thymio_bt/backends/sim/readings.py): the same floats as casting every
ray at the refresh, each ray cast once and only if read, and a read-only mapping of all seven sensors
whatever was read first."""

import math
from pathlib import Path
from types import SimpleNamespace

import pytest

from thymio_bt.backends.sim import Simulation
from thymio_bt.backends.sim.readings import lazy_scan
from thymio_bt.maze import load_maze
from thymio_bt.robot.interface import SENSOR_NAMES, Pose

#: a reading per sensor, distinct: front_left 0.01, front_center_left 0.02, ...

ROOT = Path(__file__).resolve().parents[1]


VALUES = {name: 0.01 * (i + 1) for i, name in enumerate(SENSOR_NAMES)}


def counting_reader():
    """A reader whose rays read VALUES, counting the casts of each."""
    casts: dict[str, int] = {}

    def read(name, x, y, cos, sin):
        value = VALUES[name]  # KeyError for an unknown sensor, as a RayReader
        casts[name] = casts.get(name, 0) + 1
        return value

    return SimpleNamespace(names=SENSOR_NAMES, read=read), casts


def test_a_scan_casts_only_the_sensors_read_and_each_once():
    reader, casts = counting_reader()
    scan = lazy_scan(reader, (0.1, 0.2, 1.0, 0.0))
    assert len(scan) == 7 and bool(scan) and "front_center" in scan and casts == {}
    for _ in range(3):
        assert scan["front_center"] == 0.03 and scan["rear_right"] == 0.07
    assert casts == {"front_center": 1, "rear_right": 1}
    assert list(scan) == list(SENSOR_NAMES) and casts == {"front_center": 1, "rear_right": 1}  # names only
    assert dict(scan) == VALUES
    assert casts == dict.fromkeys(SENSOR_NAMES, 1)


def test_a_scan_is_a_read_only_mapping_of_every_sensor_in_the_sensors_order():
    reader, _ = counting_reader()
    scan = lazy_scan(reader, (0.1, 0.2, 1.0, 0.0))
    assert scan["rear_left"] == 0.06  # read out of order first
    assert list(scan.keys()) == list(SENSOR_NAMES)
    assert list(scan.values()) == list(VALUES.values())
    assert list(scan.items()) == list(VALUES.items())
    assert list(reversed(scan)) == list(reversed(SENSOR_NAMES))
    assert scan == VALUES and scan == VALUES and (scan != VALUES) is False
    assert scan != {**VALUES, "front_left": 1.0}
    assert scan.get("front_right") == 0.05 and scan.get("nope") is None and scan.get("nope", 1.0) == 1.0
    assert "nope" not in scan
    copy = scan.copy()
    assert copy == VALUES and type(copy) is dict
    assert {**scan} == VALUES and (scan | {"x": 1.0}) == {**VALUES, "x": 1.0}
    assert ({"x": 1.0} | scan) == {"x": 1.0, **VALUES}
    assert repr(scan) == f"mappingproxy({VALUES!r})"
    with pytest.raises(KeyError, match="nope"):
        scan["nope"]
    with pytest.raises(TypeError):
        scan["front_left"] = 0.5  # type: ignore[index]


def test_two_scans_compare_by_their_readings():
    reader, casts = counting_reader()
    one, other = lazy_scan(reader, (0.1, 0.2, 1.0, 0.0)), lazy_scan(reader, (0.3, 0.2, 1.0, 0.0))
    assert one["front_left"] == 0.01
    assert one == other and casts == dict.fromkeys(SENSOR_NAMES, 2)


@pytest.mark.parametrize(
    "pose",
    [
        Pose(0.1, 0.1, 0.0),
        Pose(0.5, 0.3, math.pi / 2),
        Pose(0.31, 0.47, 2.5),
        Pose(0.9, 0.13, -0.4),
        Pose(0.3, 0.489, math.pi),
    ],
)
def test_rays_cast_when_read_are_the_floats_of_the_rays_cast_together(pose):
    """Each sensor alone, in any order, reads what the seven rays cast in one fan read (bit for bit)."""
    maze = load_maze(f"{ROOT}/mazes/two_parts_maze.yaml")
    sim = Simulation(maze, spawn=pose)
    entity = sim._entities[sim.robot_name]
    x, y, angle = entity.read()
    at = (x, y, math.cos(angle), math.sin(angle))
    together = sim._cast(entity, *at)
    scan = lazy_scan(sim._reader, at)
    assert [scan[name] for name in reversed(SENSOR_NAMES)] == [together[name] for name in reversed(SENSOR_NAMES)]
    assert sim.proximity() == together and any(math.isfinite(v) for v in together.values())
