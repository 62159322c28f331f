"""One home for each fact (issue 45): one angle wrap, and nothing probed with getattr that a class
can declare (``proximity_raw``, ``unrun_plugin``, ``bt_sync``, ``keep_moving``, ``failure``, ``mark``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import thymio_bt
from thymio_bt.backends.sim import Simulation
from thymio_bt.behaviours.base import ConditionBehaviour, RobotBehaviour, UnrunPlugin
from thymio_bt.behaviours.motion import MoveDistance, MoveUntilWall, Stop, TurnAngle
from thymio_bt.plan.unrun_plugins import stand_in
from thymio_bt.robot.calibrate import START, arena, calibrate
from thymio_bt.robot.interface import Robot
from thymio_bt.robot.model import COURSE

PACKAGE = Path(thymio_bt.__file__).parent
SOURCES = {p.relative_to(PACKAGE).as_posix(): p.read_text(encoding="utf-8") for p in PACKAGE.rglob("*.py")}


def test_the_angle_wrap_is_written_once():
    inlined = re.compile(r"%\s*\(\s*2(\.0)?\s*\*\s*math\.pi\s*\)|while\s+[\w.]+\s*[<>]=?\s*-?math\.pi")
    places = [path for path, text in SOURCES.items() for _ in inlined.finditer(text)]
    assert places == ["geometry.py"]  # wrap_angle itself


@pytest.mark.parametrize("name", ["proximity_raw", "unrun_plugin", "bt_sync", "keep_moving", "failure", "mark"])
def test_no_getattr_probe_for_a_declared_attribute(name):
    probe = re.compile(rf"getattr\([^)]*[\"']{name}[\"']")
    assert [path for path, text in SOURCES.items() if probe.search(text)] == []


def test_every_robot_declares_its_raw_readings():
    assert Robot.raw_readings is False and Simulation.raw_readings is True
    raw = Simulation(arena(), spawn=START, config=None)
    assert raw.proximity_raw() is None  # metres by default: declared, and None


def test_calibrate_refuses_a_robot_without_raw_readings():
    class MetresOnly(Simulation):
        raw_readings = False

    with pytest.raises(ValueError, match="gives no raw readings"):
        calibrate(MetresOnly(arena(), spawn=START), COURSE, arena(), say=lambda text: None)


def test_node_kinds_declare_what_tools_used_to_probe():
    assert issubclass(stand_in("Spin"), UnrunPlugin) and not issubclass(MoveDistance, UnrunPlugin)
    assert ConditionBehaviour.bt_sync and not RobotBehaviour.bt_sync
    for motion in (MoveUntilWall, MoveDistance, TurnAngle):
        params = motion.Params.model_validate({"keep_moving": True, **_required(motion)})
        node = motion.__new__(motion)
        node.params = params
        assert node.keeps_moving()
    assert not Stop.keeps_moving(Stop.__new__(Stop))


def _required(motion: type[RobotBehaviour]) -> dict[str, float]:
    return {"distance": 0.1} if motion is MoveDistance else {"angle": 1.0} if motion is TurnAngle else {}
