"""``thymio-bt replay LOG --mission CHANGED.yaml``, what if: the identical tree reproduces a log
exactly (several noisy seeds); a changed stop distance diverges where its command first differs,
naming MoveUntilWall, and ``--continue sim`` then equals a fresh run of the changed mission bit for
bit; the report's counterfactual section; a graded run's log against the student's fix; a log of
another mission refused, a damaged or cut one replayed up to its last whole tick, never a traceback."""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.logs import read_log
from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.run.whatif import what_if

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "maze_part1_2.yaml"
NOISE = {"noise.wheel": "0.027", "noise.range_sd": "0.001", "noise.odometry": "0.01"}


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def record(settings=None, seed=None, log=None):
    recorder = Recorder(log_path=log, statuses=True)
    return recorder.finish(Run(load_mission(MISSION, settings), seed=seed).run(on_tick=recorder))


def assert_reproduces(recording, mission):
    """Replaying ``mission`` against ``recording`` gives the same statuses and commands every tick."""
    again = Recorder(statuses=True)
    replayed = what_if(recording, mission, on_tick=again)
    assert replayed.divergence is None
    assert replayed.replayed_ticks == len(recording.samples) and replayed.simulated_ticks == 0
    assert [s["nodes"] for s in again.samples] == [s["nodes"] for s in recording.samples]
    assert [s["cmd"] for s in again.samples] == [s["cmd"] for s in recording.samples]
    assert replayed.result.status == recording.end["status"]
    return replayed


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_identical_tree_reproduces_a_noisy_simulator_log(seed, tmp_path):
    record(NOISE, seed, tmp_path / "run.jsonl")
    logged = read_log(tmp_path / "run.jsonl")
    assert any("odom" in s for s in logged.samples)  # odometry drifts: the log keeps what the tree read
    assert_reproduces(logged, load_mission(MISSION, NOISE))


def test_a_changed_stop_distance_diverges_where_its_command_first_differs():
    recorded, fresh = record(), record({"final_stop": "6cm"})
    replayed = what_if(recorded, load_mission(MISSION, {"final_stop": "6cm"}))
    found = replayed.divergence
    assert found is not None
    first = next(
        i for i, (a, b) in enumerate(zip(recorded.samples, fresh.samples, strict=True)) if a["cmd"] != b["cmd"]
    )
    assert (found.time, found.tick) == (recorded.samples[first]["t"], recorded.samples[first]["tick"])
    assert (found.node, found.kind) == ("course/part 1", "MoveUntilWall")
    assert found.recorded == recorded.samples[first]["cmd"] and found.new == pytest.approx(fresh.samples[first]["cmd"])
    # it slows down for a wall 6 cm away before the 5 cm run does: its approach speed follows the remaining gap
    assert found.new[0] < found.recorded[0]
    assert replayed.result.code == "STOPPED" and "no longer tells what the robot would see" in replayed.result.reason
    assert replayed.replayed_ticks == first + 1 and replayed.simulated_ticks == 0


def test_continue_sim_equals_a_fresh_run_of_the_changed_mission(tmp_path):
    record(log=tmp_path / "five.jsonl")
    fresh = record({"final_stop": "6cm"})
    again = Recorder(statuses=True)
    replayed = what_if(
        read_log(tmp_path / "five.jsonl"),
        load_mission(MISSION, {"final_stop": "6cm"}),
        continue_sim=True,
        on_tick=again,
    )
    assert replayed.divergence is not None and replayed.simulated_ticks > 0
    assert replayed.replayed_ticks + replayed.simulated_ticks == len(fresh.samples)
    assert "starting at the ground-truth pose" in replayed.notes[0]
    for mine, theirs in zip(again.samples, fresh.samples, strict=True):  # bit for bit, noise-free
        assert (mine["t"], mine["pose"], mine["cmd"], mine["nodes"]) == (
            theirs["t"],
            theirs["pose"],
            theirs["cmd"],
            theirs["nodes"],
        )
    assert replayed.result.final_pose_json == fresh.end["final_pose"]


def test_the_report_has_its_counterfactual_section(tmp_path):
    record(log=tmp_path / "run.jsonl")
    result = invoke(
        "replay",
        tmp_path / "run.jsonl",
        "--set",
        "final_stop=6cm",
        "--continue",
        "sim",
        "--report",
        tmp_path / "r.json",
    )
    assert result.exit_code == 1, result.output  # the 6 cm stop misses the mission's expect: 5 cm +- 3 mm
    report = json.loads((tmp_path / "r.json").read_text())
    counterfactual = report["counterfactual"]
    assert set(counterfactual) == {"divergence", "replayed_ticks", "simulated_ticks"}
    assert set(counterfactual["divergence"]) == {"time", "tick", "node", "recorded", "new"}
    assert counterfactual["divergence"]["node"] == "course/part 1"
    assert report["status"] == "FAILURE" and report["code"] == "EXPECTATION" and report["ticks"] == 327
    same = invoke("replay", tmp_path / "run.jsonl", "--mission", MISSION, "--report", tmp_path / "same.json")
    assert same.exit_code == 0 and "the verdict is exact" in same.output
    assert json.loads((tmp_path / "same.json").read_text())["counterfactual"] == {
        "divergence": None,
        "replayed_ticks": 329,
        "simulated_ticks": 0,
    }


def test_a_graded_runs_log_against_the_students_fix(tmp_path):
    student = ROOT / "examples" / "class" / "dana" / "part1_2.yaml"
    # the grade's reproduce command of dana's failed run (docs/grading.md), with --log
    args = ["--maze", ROOT / "mazes" / "two_parts_maze.yaml", "--start", "part1", "--seed", "0"]
    args += ["--set", "noise.odometry=0.01", "--set", "noise.range_sd=0.001", "--set", "noise.wheel=0.027"]
    invoke("run", student, *args, "-q", "--log", tmp_path / "graded.jsonl")
    fixed = tmp_path / "fixed.yaml"
    fixed.write_text(student.read_text().replace("distance: 7cm", "distance: 5cm"))
    result = invoke(
        "replay", tmp_path / "graded.jsonl", "--mission", fixed, "--continue", "sim", "--report", tmp_path / "r.json"
    )
    assert "Traceback" not in result.output
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["counterfactual"]["divergence"]["node"] == "mission/part 1"
    assert report["counterfactual"]["simulated_ticks"] > 0
    stop = next(e for e in report["events"] if e["kind"] == "behaviour_end" and e["path"] == "mission/part 1")
    assert stop["range"] == pytest.approx(0.05, abs=0.005)  # the fix stops at 5 cm, where the graded run did not


def test_a_log_of_another_mission_is_refused(tmp_path):
    assert invoke("run", ROOT / "missions" / "square.yaml", "-q", "--log", tmp_path / "square.jsonl").exit_code == 0
    result = invoke("replay", tmp_path / "square.jsonl", "--mission", MISSION)
    assert result.exit_code == 2
    assert "the log is of another tree" in result.output and "which this mission lacks" in result.output
    assert "Traceback" not in result.output


def test_a_damaged_or_cut_log_is_replayed_up_to_its_last_whole_tick(tmp_path):
    record(log=tmp_path / "run.jsonl")
    lines = (tmp_path / "run.jsonl").read_text().splitlines()
    damaged = tmp_path / "damaged.jsonl"
    damaged.write_text("\n".join(lines[:101] + ["{broken"] + lines[102:]) + "\n")
    result = invoke("replay", damaged, "--mission", MISSION)
    assert result.exit_code == 1, result.output
    assert "damaged.jsonl:102: damaged line; kept the 100 ticks before it" in result.output
    assert "the log is damaged at line 102 at 9.9 s (tick 100) with the tree still running" in result.output
    cut = tmp_path / "cut.jsonl"
    cut.write_text("\n".join(lines[:151]) + "\n" + lines[151][:30])
    result = invoke("replay", cut, "--mission", MISSION, "--continue", "sim")
    assert "the log is cut short; kept its 150 ticks" in result.output
    assert (
        "the log is cut short at 14.9 s (tick 150) with the tree still running; simulated from there" in result.output
    )
    assert result.exit_code == 0 and "Traceback" not in result.output  # the simulator finished the run


def test_a_log_with_junk_entity_events_is_replayed_without_a_traceback(tmp_path):
    record(log=tmp_path / "run.jsonl")
    lines = (tmp_path / "run.jsonl").read_text().splitlines()
    end = json.loads(lines[-1])
    end["events"] = [
        {"kind": "delete_entity", "t": None},
        {"kind": "spawn_entity", "t": 4.4, "entity": ["thymio"], "pose": {"x": "a"}},
        {"kind": "collision", "t": 1e400},
    ]
    junk = tmp_path / "junk.jsonl"
    junk.write_text("\n".join([*lines[:-1], json.dumps(end)]) + "\n")
    result = invoke("replay", junk, "--mission", MISSION, "--report", tmp_path / "r.json")
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    divergence = json.loads((tmp_path / "r.json").read_text())["counterfactual"]["divergence"]
    assert divergence["node"] == "course/DeleteEntity" and divergence["new"] == "delete thymio"


def test_a_rosbag_log_replays_within_its_rounding(tmp_path):
    import _require

    _require.module("rosbags")
    noise = {k: v for k, v in NOISE.items() if k != "noise.odometry"}  # a bag keeps no odometry apart from its pose
    record(noise, 4, tmp_path / "run.jsonl")
    assert invoke("export", tmp_path / "run.jsonl", "-o", tmp_path / "run.mcap").exit_code == 0
    bag = read_log(tmp_path / "run.mcap")
    assert bag.header["exact"] is False  # float32 scans
    assert what_if(bag, load_mission(MISSION, noise), tolerance=1e-9).divergence is not None
    replayed = what_if(bag, load_mission(MISSION, noise))
    assert replayed.divergence is None and replayed.replayed_ticks == len(bag.samples)
    result = invoke(
        "replay", tmp_path / "run.mcap", "--mission", MISSION, *[f"--set={k}={v}" for k, v in noise.items()]
    )
    assert "within 0.0001 (this log's numbers are rounded)" in result.output and result.exit_code == 0


def test_a_run_that_timed_out_replays_to_its_time_limit(tmp_path):
    record({"time_limit": "5"}, log=tmp_path / "short.jsonl")
    replayed = what_if(read_log(tmp_path / "short.jsonl"), load_mission(MISSION, {"time_limit": "5"}))
    assert replayed.divergence is None and replayed.replayed_ticks == 50
    assert (replayed.result.status, replayed.result.code) == ("TIMEOUT", "TIMEOUT")


def test_a_log_written_before_exact_numbers_replays_within_its_rounding(tmp_path):
    recording = record(log=tmp_path / "run.jsonl")
    lines = (tmp_path / "run.jsonl").read_text().splitlines()

    def rounded(value):
        if isinstance(value, float):
            return round(value, 6)
        if isinstance(value, dict):
            return {k: rounded(v) for k, v in value.items()}
        return [rounded(v) for v in value] if isinstance(value, list) else value

    header = json.loads(lines[0])
    del header["backend"], header["latency"]  # what logs held before
    old = tmp_path / "old.jsonl"
    old.write_text("\n".join([json.dumps(header)] + [json.dumps(rounded(json.loads(x))) for x in lines[1:]]) + "\n")
    logged = read_log(old)
    assert what_if(logged, load_mission(MISSION), tolerance=1e-9).divergence is not None
    replayed = what_if(logged, load_mission(MISSION))
    assert replayed.divergence is None and replayed.replayed_ticks == len(recording.samples)


def test_a_log_of_another_tick_rate_or_with_a_junk_header_is_said_not_raised(tmp_path):
    record(log=tmp_path / "run.jsonl")
    result = invoke("replay", tmp_path / "run.jsonl", "--mission", MISSION, "--set", "tick_hz=20")
    assert result.exit_code == 2 and "recorded at 10 Hz, the mission ticks at 20 Hz" in result.output
    lines = (tmp_path / "run.jsonl").read_text().splitlines()
    header = {**json.loads(lines[0]), "seed": "lucky", "latency": "slow"}
    junk = tmp_path / "junk.jsonl"
    junk.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    result = invoke("replay", junk, "--mission", MISSION)
    assert result.exit_code == 0 and "the verdict is exact" in result.output, result.output


def test_continue_sim_simulates_the_robot_the_log_was_made_with(tmp_path):
    record({"robot": "enki"}, log=tmp_path / "enki.jsonl")
    logged = read_log(tmp_path / "enki.jsonl")
    logged.header.update(backend="playground", latency=0.2)  # a Playground log: Enki's robot, late by 0.2 s
    seen = []

    def look(run):
        live = run.backend.live
        seen.append((live and live.model.name, run.backend.latency))

    what_if(logged, load_mission(MISSION, {"final_stop": "6cm"}), continue_sim=True, on_tick=look)
    assert seen[0] == (None, 0.2) and seen[-1] == ("enki", 0.0)  # the simulator's Enki, on time


def test_a_log_of_another_robot_is_re_ticked_as_that_robot(tmp_path):
    # a log made with --robot enki, replayed against the mission file (the course robot): the tree is
    # re-ticked, and simulated on, as the robot the log header names, not as the mission's
    record({"robot": "enki"}, log=tmp_path / "enki.jsonl")
    logged = read_log(tmp_path / "enki.jsonl")
    assert logged.header["robot"]["name"] == "enki"
    models = set()
    replayed = what_if(logged, load_mission(MISSION), on_tick=lambda run: models.add(run.backend.model.name))
    assert models == {"enki"}
    assert replayed.divergence is None
