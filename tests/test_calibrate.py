"""thymio-bt calibrate: a profile measured on a backend, then used with --robot FILE. In the
simulation (fast) and against the Aseba Playground (real time, CI installs it)."""

import subprocess
import sys

import _require
import pytest

from thymio_bt.errors import UserError
from thymio_bt.mission import load_mission
from thymio_bt.robot.calibrate import table_rows
from thymio_bt.robot.model import ENKI, robot_model
from thymio_bt.run.runner import Run


def _calibrate(tmp_path, backend, *args):
    out = tmp_path / "measured.yaml"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "thymio_bt",
            "calibrate",
            "--backend",
            backend,
            "--robot",
            "enki",
            "-o",
            str(out),
            *args,
        ],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    return out, robot_model(str(out))


def _check_against_enki(model, reading_tolerance):
    for cm in range(1, 13):
        assert model.calibration.to_raw(cm / 100) == pytest.approx(
            ENKI.calibration.to_raw(cm / 100), rel=reading_tolerance
        ), f"{cm} cm"
    assert model.metres_per_unit == pytest.approx(ENKI.metres_per_unit, rel=0.03)
    assert model.wheel_separation == pytest.approx(ENKI.wheel_separation, rel=0.03)


def test_calibrating_the_simulated_enki_robot_finds_its_numbers(tmp_path):
    path, model = _calibrate(tmp_path, "sim")
    _check_against_enki(model, 0.02)
    assert model.name == "measured" and model.hull == ENKI.hull  # the rest is the base model's
    assert robot_model(str(path)) is model


def test_a_measured_profile_runs_a_mission(tmp_path):
    path, _ = _calibrate(tmp_path, "sim")
    mission = tmp_path / "m.yaml"
    mission.write_text(
        f"maze: two_parts_maze\nstart: part1\nrobot: {path.name}\ntree:\n  MoveUntilWall: {{distance: 5cm}}\n"
    )
    result = Run(load_mission(mission)).run()
    assert result.status == "SUCCESS"
    assert result.final_proximity["front_center"] == pytest.approx(0.05, abs=0.003)


def test_a_bad_profile_is_located(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("base: enky\nname: x\nwheel_sep: 0.09\n")
    with pytest.raises(UserError) as info:
        robot_model(str(path))
    text = str(info.value)
    assert f"{path}:1:1: 'base'" in text and "did you mean 'enki'?" in text
    assert f"{path}:3:1: 'wheel_sep'" in text and "did you mean 'wheel_separation'?" in text
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: two_parts_maze\nstart: part1\nrobot: missing.yaml\ntree:\n  Stop: {}\n")
    with pytest.raises(UserError, match="missing.yaml"):
        load_mission(mission)


def test_the_table_is_the_median_per_bin_strictly_decreasing_and_ends_at_zero():
    samples = [
        (0.0098, 4400),
        (0.0101, 4420),
        (0.0102, 4380),
        (0.02, 4300),
        (0.0248, 4310),
        (0.03, 4000),
        (0.145, 1200),
        (0.15, 0),
        (0.16, 0),
    ]
    rows = table_rows(samples)
    assert rows == [(0.01, 4400.0), (0.02, 4300.0), (0.03, 4000.0), (0.145, 1200.0), (0.15, 0.0)]
    with pytest.raises(ValueError, match="never saw the wall go out of range"):
        table_rows([(0.01, 4400), (0.02, 4300)])


def test_calibrating_on_the_aseba_playground_matches_enki(tmp_path):
    """The issue's acceptance: Enki's curve within 5 % from 1 to 12 cm, the speed scale within 3 %."""
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    _require.module("jeepney")
    _, model = _calibrate(tmp_path, "playground")
    _check_against_enki(model, 0.05)
