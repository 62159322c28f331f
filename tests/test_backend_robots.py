"""Each backend drives its own robot: a real Thymio (aseba, tdm) is ``real`` and the Playground's is
``enki`` when the mission names no robot (an explicit ``robot: course`` or ``--robot course`` is
kept), and the model chosen (a name or a measured profile) is the one behaviours read as ``robot.model``. Also the
``placed`` option, for a run with nobody to place the robot."""

import math
from pathlib import Path

import _require
import pytest

from thymio_bt.backends import backend_kind, robot_for
from thymio_bt.backends.real import AsebaDevice, ThymioRobot
from thymio_bt.backends.real.aseba import AsebaNode
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose, RequestState
from thymio_bt.robot.model import ENKI, REAL

ROOT = Path(__file__).resolve().parents[1]


class StillNode(AsebaDevice):
    """A robot standing still, 5 cm from a wall by Webots' table."""

    def __init__(self):
        self.writes = []

    def set_motors(self, left, right):
        self.writes.append((left, right))

    def read_prox(self):
        return [0, 0, 2570, 0, 0, 0, 0]

    def read_wheel_speeds(self):
        return 0, 0


def _profile(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("base: real\nname: mine\nmetres_per_unit: 0.00038\nwheel_separation: 0.0921\n")
    return str(path)


def _aseba(monkeypatch, overrides, options=None):
    node = StillNode()
    monkeypatch.setattr(AsebaNode, "connect", classmethod(lambda cls, device="", timeout=5.0: node))
    mission = load_mission(f"{ROOT}/missions/square.yaml", overrides)
    return backend_kind("aseba").create(mission, 0, options or {}), node


@pytest.mark.parametrize(
    "robot, expected", [(None, "real"), ("course", "course"), ("enki", "enki"), ("profile", "mine")]
)
def test_the_aseba_backend_drives_the_model_chosen_and_real_by_default(monkeypatch, tmp_path, capsys, robot, expected):
    """ThymioRobot set no model: behaviours (which read robot.model) drove a real Thymio with the
    course robot's sensor poses, and the conversions used the course's numbers."""
    overrides = {} if robot is None else {"robot": _profile(tmp_path) if robot == "profile" else robot}
    backend, node = _aseba(monkeypatch, overrides)
    with backend:
        assert backend.model.name == expected
        assert backend.speed_scale == 1.0  # every number from the model: no copies to disagree with it
    said = capsys.readouterr().err
    assert ("robot model 'real'" in said) == (robot is None)
    if expected == "mine":
        assert backend.model.wheel_separation == 0.0921 and backend.model.sensors == REAL.sensors


def test_the_tdm_backend_drives_real_by_default(monkeypatch):
    made = {}

    def connect(cls, host=None, port=None, password=None, **kwargs):
        made.update(kwargs)
        return ThymioRobot(StillNode(), **kwargs)

    monkeypatch.setattr(ThymioRobot, "connect", classmethod(connect))
    backend = backend_kind("tdm").create(load_mission(f"{ROOT}/missions/square.yaml"), 0, {"placed": "true"})
    assert backend.model is REAL and made["placed"] is True


def test_a_thymio_robot_without_a_model_is_a_real_thymio():
    robot = ThymioRobot(StillNode(), spawn=Pose(0.1, 0.1, 0.0), clock=lambda: 0.0, sleep=lambda s: None)
    assert robot.model is REAL
    assert robot.proximity()["front_center"] == pytest.approx(0.05)


def test_a_behaviour_reads_the_backends_model(monkeypatch):
    """The grid behaviours take sensor poses from robot.model: on a real Thymio, the real model's."""
    from thymio_bt.behaviours import Context

    backend, _ = _aseba(monkeypatch, {"robot": "enki"})
    with backend:
        assert Context(robot=backend, entities=backend).robot.model is ENKI


def test_robot_for_keeps_a_named_robot_and_replaces_the_course_on_other_robots():
    said = []
    mission = load_mission(f"{ROOT}/missions/square.yaml")
    assert robot_for(mission, "sim", said.append).name == "course" and said == []
    assert robot_for(mission, "playground", said.append) is ENKI and "--backend playground" in said[0]
    enki = load_mission(f"{ROOT}/missions/square.yaml", {"robot": "enki"})
    assert robot_for(enki, "aseba", said.append) is ENKI and len(said) == 1


def test_an_explicit_course_robot_is_kept_on_another_backend(tmp_path):
    """``--robot course`` (or ``robot: course``) is a choice, not the absence of one: the Playground
    drives the course's model then, and says nothing; a mission naming none gets Enki's."""
    from thymio_bt.btcpp.export import mission_settings

    square = f"{ROOT}/missions/square.yaml"
    written = tmp_path / "m.yaml"
    written.write_text("maze: arena\nstart: [0.6, 0.6, 0]\nrobot: course\ntree: {Wait: {seconds: 1}}\n")
    for mission in (load_mission(square, {"--robot": "course"}), load_mission(square, {"robot": "course"})):
        said: list[str] = []
        assert mission.robot == "course" and robot_for(mission, "playground", said.append).name == "course"
        assert said == [] and mission_settings(mission, tmp_path)["robot"] == "course"
    assert robot_for(load_mission(written), "playground", print).name == "course"
    unnamed = load_mission(square)
    assert unnamed.robot is None and "robot" not in mission_settings(unnamed, tmp_path)
    assert robot_for(unnamed, "playground", lambda _: None) is ENKI


def test_placed_skips_the_first_prompt_only_and_says_how_without_an_operator():
    asked = []

    def absent(prompt):
        asked.append(prompt)
        raise EOFError

    robot = ThymioRobot(StillNode(), clock=lambda: 0.0, sleep=lambda s: None, ask=absent, say=lambda s: None)
    first = robot.request_spawn("thymio", Pose(0.1, 0.1, 0.0))
    robot.advance(0.0)
    assert first.state is RequestState.FAILED and "--backend-opt placed=true" in first.reason
    placed = ThymioRobot(
        StillNode(), clock=lambda: 0.0, sleep=lambda s: None, ask=absent, say=lambda s: None, placed=True
    )
    start = placed.request_spawn("thymio", Pose(0.1, 0.1, 0.0))
    placed.advance(0.0)
    assert start.state is RequestState.SUCCEEDED and placed.pose() == Pose(0.1, 0.1, 0.0)
    assert len(asked) == 1  # the placed robot was not asked about
    placed.request_delete("thymio")
    placed.advance(0.0)
    again = placed.request_spawn("thymio", Pose(0.5, 0.3, math.pi / 2))
    placed.advance(0.0)
    assert again.state is RequestState.FAILED and "needs someone at the keyboard" in again.reason


def test_the_playground_without_a_robot_drives_enki(tmp_path):
    """The issue's case: --backend playground without --robot used the course's sensor model on
    Enki's robot (one run reported SUCCESS after pushing a wall for 41 s). Through Webots' table
    Enki's readings place walls too close: a 5 cm stop stopped about 7.4 cm from the wall."""
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    _require.module("jeepney")
    from thymio_bt.run.runner import Run
    from thymio_bt.run.verdict import front_gap

    (tmp_path / "corridor.txt").write_text("o---o---o---o---o---o\n| S                 |\no---o---o---o---o---o\n")
    (tmp_path / "m.yaml").write_text(
        "name: corridor\nmaze: corridor.txt\nstart: start\ntime_limit: 30\n"
        "tree:\n  MoveUntilWall: {distance: 5cm, speed: 8cm/s}\n"
    )
    mission = load_mission(tmp_path / "m.yaml")
    backend = backend_kind("playground").create(mission, 0, {})
    result = Run(mission, backend=backend).run()  # closes the backend (and the Playground) however it ends
    assert backend.model is ENKI and backend.speed_scale == 0.985  # its units cover 0.985 of Enki's
    assert result.status == "SUCCESS", result.reason
    gap = front_gap(mission.maze, ENKI, result.final_pose)
    assert gap == pytest.approx(0.05, abs=0.01)
