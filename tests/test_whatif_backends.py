"""What if and compare with the other backends' logs: a Playground run and a ROS 2 run replay
exactly against their own tree (every status, every command); the simulator against the Playground
for maze_part1_2 gives the phase table and the divergence docs/sim_to_real.md records; a ROS 2 log,
which has no ground truth, continues in the simulator from its odometry and says so.

The Playground runs in real time (about 55 s a run: marked slow, CI runs them); ROS 2 as
tests/test_ros2.py does (THYMIO_BT_ROS2_ENV, its own domain)."""

import json
from pathlib import Path

import _require
import pytest
from click.testing import CliRunner
from test_ros2 import _cli, ros2_env, serving  # noqa: F401  (ros2_env: the fixture)

from thymio_bt.cli import main
from thymio_bt.logs import read_log
from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.run.whatif import what_if

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "maze_part1_2.yaml"


def reproduces(log: Path, settings: dict) -> None:
    """The mission's own tree, replayed against ``log``: the same statuses and commands every tick."""
    recording = read_log(log)
    again = Recorder(statuses=True)
    replayed = what_if(recording, load_mission(MISSION, settings), on_tick=again)
    assert replayed.divergence is None, replayed.divergence
    assert replayed.replayed_ticks == len(recording.samples)
    assert [s["nodes"] for s in again.samples] == [s["nodes"] for s in recording.samples]
    assert [s["cmd"] for s in again.samples] == [s["cmd"] for s in recording.samples]
    assert replayed.result.status == recording.end["status"] == "SUCCESS"


@pytest.fixture(scope="module")
def playground_log(tmp_path_factory):
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    log = tmp_path_factory.mktemp("playground") / "playground.jsonl"
    args = ["run", str(MISSION), "--backend", "playground", "--robot", "enki", "-q", "--log", str(log)]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    return log


@pytest.mark.slow
def test_a_playground_log_replays_exactly(playground_log):
    assert read_log(playground_log).header["backend"] == "playground"
    assert any("odom" in s for s in read_log(playground_log).samples)  # its odometry is not its ground truth
    reproduces(playground_log, {"robot": "enki"})


@pytest.mark.slow
def test_the_simulator_against_the_playground(tmp_path):
    _require.program("asebaplayground")
    out, plot = tmp_path / "compare.json", tmp_path / "compare.png"
    args = ["compare", str(MISSION), "--backends", "sim,playground", "--set", "robot=enki", "--json", str(out)]
    result = CliRunner().invoke(main, [*args, "--plot", str(plot)])
    assert result.exit_code == 1, result.output  # the Playground's clock runs its own way: times differ past 0.5 s
    assert "sim: SUCCESS" in result.output and "playground: SUCCESS" in result.output
    data = json.loads(out.read_text())
    assert all(p["a"] is not None and p["b"] is not None for p in data["phases"])  # the same phases, in both
    part1 = data["phases"][0]
    assert part1["node"] == "course/part 1" and abs(part1["diff"]["front"]) < 0.005
    turns = [p for p in data["phases"] if p["node"].endswith("TurnAngle")]
    turned = [(p["a"]["turned_deg"], p["b"]["turned_deg"]) for p in turns]
    assert len(turns) == 4 and all(abs(b - a) < 5 for a, b in turned), turned
    divergence = data["divergence"]
    assert divergence is not None and divergence["a"]["pose_source"] == divergence["b"]["pose_source"] == "ground truth"
    assert plot.stat().st_size > 10_000


def test_a_ros2_log_replays_exactly_and_continues_from_its_odometry(ros2_env, tmp_path):  # noqa: F811
    log = tmp_path / "ros2.jsonl"
    with serving(ros2_env) as domain:
        args = ["run", str(MISSION), "--backend", "ros2", "-q", "--log", str(log)]
        result = _cli(ros2_env / "bin" / "python", *args, domain=domain)
    assert result.returncode == 0, result.stderr
    assert read_log(log).header["backend"] == "ros2"
    reproduces(log, {})
    changed = what_if(read_log(log), load_mission(MISSION, {"final_stop": "6cm"}), continue_sim=True)
    assert changed.divergence is not None and changed.divergence.node == "course/part 1"
    assert "the odometry pose (no ground truth)" in changed.notes[0]
    assert changed.simulated_ticks > 0
