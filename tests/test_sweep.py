"""thymio-bt sweep: the DESIGN.md JSON contract, determinism, and the executor boundary."""

import json
from pathlib import Path

from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.run.sweep import LocalPool, run_job, sweep

ROOT = Path(__file__).resolve().parents[1]


def test_sweep_json_contract_and_noise_on_by_default(tmp_path):
    out = tmp_path / "sweep.json"
    result = CliRunner().invoke(
        main,
        [
            "sweep",
            f"{ROOT}/missions/square.yaml",
            "--runs",
            "6",
            "--seed-start",
            "10",
            "--out",
            str(out),
            "--workers",
            "2",
        ],
    )
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert data["runs"] == 6 and data["successes"] == 6 and data["success_rate"] == 1.0
    assert [r["seed"] for r in data["results"]] == list(range(10, 16))
    assert set(data["results"][0]) >= {"seed", "status", "sim_time", "final_pose"}
    assert data["noise"]["wheel"] > 0 and data["noise"]["range_sd"] > 0
    assert len({json.dumps(r["final_pose"]) for r in data["results"]}) == 6  # the noise did something
    assert "6/6 succeeded" in result.output


def test_the_same_sweep_gives_the_same_results_serial_or_parallel():
    serial = sweep(f"{ROOT}/missions/square.yaml", 4, executor=LocalPool(1)).to_json()
    parallel = sweep(f"{ROOT}/missions/square.yaml", 4, executor=LocalPool(2)).to_json()
    for data in (serial, parallel):
        data.pop("wall_time"), data.pop("aggregate_real_time_factor")
    assert serial == parallel


def test_any_pool_with_imap_unordered_can_run_a_sweep():
    class Reversed:  # stands for Ray's or Dask's pool: results out of order
        def imap_unordered(self, fn, jobs):
            return iter([fn(job) for job in reversed(list(jobs))])

    result = sweep(f"{ROOT}/missions/square.yaml", 3, executor=Reversed())
    assert [r["seed"] for r in result.results] == [0, 1, 2]


def test_noise_can_be_switched_off_with_set():
    result = sweep(
        f"{ROOT}/missions/square.yaml",
        2,
        overrides={"noise.wheel": "0", "noise.range_sd": "0", "noise.odometry": "0"},
        executor=LocalPool(1),
    )
    assert result.results[0]["final_pose"] == result.results[1]["final_pose"]


def test_run_job_reports_the_first_stop_error():
    from thymio_bt.run.sweep import Job

    summary = run_job(Job(f"{ROOT}/missions/maze_part1_2.yaml", 0))
    assert summary["status"] == "SUCCESS"
    assert summary["first_stop_error"] < 0.001


def test_a_sweep_row_holds_the_keys_its_type_declares_with_the_runs_enums():
    """A row is a SweepRow (a TypedDict mypy checks), its status and code the run's enums until JSON."""
    from thymio_bt.behaviours.base import FailureCode
    from thymio_bt.run.result import RunStatus
    from thymio_bt.run.sweep import Job, SweepRow

    row = run_job(Job(f"{ROOT}/missions/maze_part1_2.yaml", 0, overrides=(("time_limit", "5"),), coverage=True))
    assert list(row) == list(SweepRow.__annotations__) and SweepRow.__optional_keys__ == {"coverage"}
    assert row["status"] is RunStatus.TIMEOUT and row["code"] is FailureCode.TIMEOUT
    assert row["final_pose"] == {"x": 0.5, "y": 0.35, "yaw": 1.570796}


def test_a_matrix_sweeps_every_combination_and_tabulates_it(tmp_path):
    import json

    from click.testing import CliRunner

    from thymio_bt.cli import main

    out = tmp_path / "m.json"
    result = CliRunner().invoke(
        main,
        [
            "sweep",
            f"{ROOT}/missions/maze_bonus.yaml",
            "--runs",
            "3",
            "--workers",
            "1",
            "--matrix",
            "robot=course,enki",
            "--matrix",
            "sensor_model=rays,cone",
            "--out",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert [c["settings"] for c in data["cells"]] == [
        {"robot": "course", "sensor_model": "rays"},
        {"robot": "course", "sensor_model": "cone"},
        {"robot": "enki", "sensor_model": "rays"},
        {"robot": "enki", "sensor_model": "cone"},
    ]
    assert all(c["runs"] == 3 for c in data["cells"])
    assert data["cells"][0]["success_rate"] == 1.0 and data["cells"][0]["final_error_max"] < 0.01
    assert "median err" in result.output and result.output.count("course") >= 2


def test_a_bad_matrix_axis_is_a_user_error():
    from click.testing import CliRunner

    from thymio_bt.cli import main

    result = CliRunner().invoke(main, ["sweep", f"{ROOT}/missions/square.yaml", "--matrix", "robot"])
    assert result.exit_code == 2 and "--matrix expects NAME=VALUE,VALUE" in result.output
    result = CliRunner().invoke(main, ["sweep", f"{ROOT}/missions/square.yaml", "--matrix", "robot=course,marvin"])
    assert result.exit_code == 2 and "robot must be one of" in result.output


def test_a_bad_matrix_value_is_said_at_matrix_and_nothing_comes_before_an_error(tmp_path):
    bad = CliRunner().invoke(main, ["sweep", "square", "--runs", "2", "--matrix", "robot=course,nosuch"])
    assert bad.exit_code == 2 and bad.output.startswith("error: --matrix: robot must be one of"), bad.output
    missing = CliRunner().invoke(main, ["sweep", str(tmp_path / "none.yaml"), "--runs", "2"])
    assert missing.exit_code == 2 and missing.output.startswith("error: ") and "runs" not in missing.output


def test_the_first_stop_error_is_read_from_what_a_behaviour_reports_not_its_name(tmp_path):
    """first_stop_error matched ``name == "MoveUntilWall"``: a plugin's stop at a wall under a name of
    its own (a subclass, which reports what its base reports) was not counted."""
    from thymio_bt.run.sweep import Job

    (tmp_path / "stops.py").write_text(
        "from thymio_bt.behaviours.motion import MoveUntilWall\n\n\n"
        "class StopAtWall(MoveUntilWall):\n    'MoveUntilWall under a name of its own.'\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [stops.py]\ntree: {StopAtWall: {distance: 5cm}}\n")
    summary = run_job(Job(str(mission), 0))
    assert summary["status"] == "SUCCESS" and summary["first_stop_error"] is not None
    assert summary["first_stop_error"] < 0.01
