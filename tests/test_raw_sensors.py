"""Missions against a real Thymio's raw readings: sensor_model: raw and thresholds in raw units."""

from pathlib import Path

import pytest

from thymio_bt.errors import UserError
from thymio_bt.inputs.units import UnitError, parse_value
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]


def test_a_raw_threshold_is_the_distance_at_which_the_table_gives_that_reading():
    assert parse_value("2570 raw").value == pytest.approx(0.05)  # Webots' table at 5 cm
    assert parse_value("3400raw").kind == "length"
    assert 0.030 < parse_value("3400 raw").value < 0.034  # "about 3400 at 3 cm"


@pytest.mark.parametrize("text", ["0 raw", "5000 raw", "2*1700 raw", "3400 raw + 1cm", "-3400 raw"])
def test_raw_readings_stand_alone_and_in_range(text):
    with pytest.raises(UnitError) as err:
        parse_value(text)
    assert err.value.hint


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_course_mission_runs_unchanged_on_raw_readings_with_a_raw_threshold(tmp_path, seed):
    mission = tmp_path / "raw.yaml"
    mission.write_text(
        "name: raw\nmaze: two_parts_maze\nstart: part1\nsensor_model: raw\n"
        "tree:\n  MoveUntilWall: {speed: 10cm/s, distance: 2570 raw}\n"
    )
    result = Run(load_mission(mission), seed=seed).run()
    assert result.status == "SUCCESS" and result.collisions == 0
    # the real wall distance (the ideal ray), not the noisy reading, is within 1.5 mm of 5 cm
    assert result.final_pose.x == pytest.approx(0.4893, abs=0.0015)


def test_the_course_missions_also_succeed_in_raw_mode():
    for path in (f"{ROOT}/missions/maze_part1_2.yaml", f"{ROOT}/missions/maze_bonus.yaml"):
        result = Run(load_mission(path, {"sensor_model": "raw"})).run()
        assert result.status == "SUCCESS" and result.collisions == 0, path


def test_sensor_model_must_be_known():
    with pytest.raises(UserError) as err:
        load_mission(f"{ROOT}/missions/square.yaml", {"sensor_model": "lidar"})
    assert "sensor_model must be one of rays, metres, raw, cone" in str(err.value)
