"""A run's result is typed inside the package (a RunStatus, FailureCode members, a Pose) and JSON
only where it is written: the report and the log's end, byte for byte what they were as strings and
dicts (tests/data/golden_run: written by the code before the types, wall-clock fields zeroed)."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from thymio_bt.behaviours.base import FailureCode
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.run.result import EndKind, RunOutcome, RunStatus
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "data" / "golden_run"
#: the golden runs: their name, and the --set options that make them
RUNS = {"success": [], "timeout": ["--set", "time_limit=5"]}


def _wall_clock_zeroed(text: str) -> str:
    text = re.sub(r'"wall_time": [^,\n]+,', '"wall_time": 0,', text)
    return re.sub(r'"real_time_factor": [^,\n]+,', '"real_time_factor": 0,', text)


@pytest.mark.parametrize("name", RUNS)
def test_the_report_and_the_logs_end_are_the_golden_bytes(name, tmp_path):
    report, log = tmp_path / "report.json", tmp_path / "log.jsonl"
    command = [sys.executable, "-m", "thymio_bt", "run", str(ROOT / "missions" / "maze_part1_2.yaml"), "-q"]
    command += ["--seed", "3", "--report", str(report), "--log", str(log), *RUNS[name]]
    done = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == (0 if name == "success" else 1), done.stderr
    assert _wall_clock_zeroed(report.read_text()) == (GOLDEN / f"report_{name}.json").read_text()
    assert log.read_text().splitlines()[-1] + "\n" == (GOLDEN / f"log_end_{name}.json").read_text()


def test_a_results_status_code_and_final_pose_are_typed():
    result = Run(load_mission(f"{ROOT}/missions/maze_part1_2.yaml", {"time_limit": "5"}), seed=3).run()
    assert result.status is RunStatus.TIMEOUT and result.code is FailureCode.TIMEOUT
    assert result.final_pose == Pose(0.5, 0.35, 1.570796)
    assert result.status == "TIMEOUT" and f"{result.status}" == "TIMEOUT"  # users' string comparisons hold
    report = result.report()
    assert report["status"] is RunStatus.TIMEOUT and report["final_pose"] == {"x": 0.5, "y": 0.35, "yaw": 1.570796}


def test_a_success_that_misses_its_expectations_is_a_failure_member(tmp_path):
    text = (ROOT / "missions" / "maze_part1_2.yaml").read_text().replace("expect:\n", "expect:\n  max_time: 10s\n")
    text = text.replace("../mazes/", f"{ROOT}/mazes/")
    (tmp_path / "lib").symlink_to(ROOT / "missions" / "lib")
    (tmp_path / "late.yaml").write_text(text)
    result = Run(load_mission(str(tmp_path / "late.yaml")), seed=3).run()
    assert result.status is RunStatus.FAILURE and result.code is FailureCode.EXPECTATION
    assert result.expectations == ["max_time: took 32.8 s, more than 10 s"]


def test_verdicts_and_endings_speak_run_statuses():
    assert EndKind.TIMEOUT.report_status is RunStatus.TIMEOUT
    assert {kind.report_status for kind in EndKind if kind is not EndKind.TIMEOUT} == {RunStatus.FAILURE}
    assert RunOutcome(RunStatus.SUCCESS).status is RunStatus.SUCCESS
