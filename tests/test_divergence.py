"""The first divergence of two runs (thymio_bt.run.divergence): none for a run and itself, the first
differing tick for two seeds or a changed stop distance, poses past the tolerances, a run that
ends first, differing tick rates, and which pose (ground truth or odometry) was compared."""

import dataclasses
import math

import pytest

from thymio_bt.logs import read_log
from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.run.divergence import first_divergence, pose_source
from thymio_bt.run.runner import Run

NOISE = {"noise.wheel": "0.027", "noise.range_sd": "0.001", "noise.odometry": "0.01"}


def record(seed=1, **settings):
    recorder = Recorder(statuses=True)
    return recorder.finish(Run(load_mission("maze_part1_2", settings), seed=seed).run(on_tick=recorder))


@pytest.fixture(scope="module")
def noisy():
    return record(1, **NOISE), record(2, **NOISE)


def test_a_run_and_itself_do_not_diverge(noisy):
    assert first_divergence(noisy[0], noisy[0]) is None


def test_two_seeds_diverge_at_the_first_differing_tick(noisy):
    a, b = noisy
    found = first_divergence(a, b)
    assert found is not None
    index = next(i for i, s in enumerate(a.samples) if s["tick"] == found.tick)
    for sa, sb in zip(a.samples[:index], b.samples[:index], strict=True):  # the same before it
        assert sa["nodes"] == sb["nodes"]
        assert math.hypot(sa["pose"]["x"] - sb["pose"]["x"], sa["pose"]["y"] - sb["pose"]["y"]) <= 0.01
    sa, sb = a.samples[index], b.samples[index]
    differs = sa["nodes"] != sb["nodes"] or math.dist(sa["pose"].values(), sb["pose"].values()) > 0.01
    assert differs
    assert found.time == sa["t"]
    assert found.a.pose == sa["pose"] and found.b.pose == sb["pose"]
    assert found.a.pose_source == found.b.pose_source == "ground truth"


def test_a_changed_stop_distance_names_the_node_that_stopped_first():
    found = first_divergence(record(), record(final_stop="6cm"))
    assert found is not None
    assert (found.time, found.tick) == (4.2, 43)
    assert found.reason.startswith("course/part 1: RUNNING in A, SUCCESS in B")
    assert found.a.running == ["course/part 1"] and found.b.running == ["course/DeleteEntity"]
    ends = {"a": found.a.to_json(), "b": found.b.to_json()}
    assert found.to_json() == {"time": 4.2, "tick": 43, "reason": found.reason, **ends}
    assert list(ends["a"]) == ["tick", "time", "running", "pose", "pose_source", "cmd"]  # compare --json's order
    assert found.mark() == {"time": 4.2, "tick": 43, "reason": found.reason}  # what view and the notebook mark


def test_poses_past_the_tolerance_diverge_and_the_tolerance_is_configurable():
    a = record()
    b = dataclasses.replace(a, samples=[dict(s) for s in a.samples])
    b.samples[10] = {**b.samples[10], "pose": {**b.samples[10]["pose"], "x": b.samples[10]["pose"]["x"] + 0.013}}
    found = first_divergence(a, b)
    assert found is not None and found.tick == a.samples[10]["tick"]
    assert found.reason == "poses 1.3 cm apart (ground truth)"
    assert first_divergence(a, b, distance=0.02) is None
    b.samples[10]["pose"] = {**a.samples[10]["pose"], "yaw": a.samples[10]["pose"]["yaw"] + math.radians(6)}
    assert first_divergence(a, b).reason == "headings 6.0 degrees apart (ground truth)"
    assert first_divergence(a, b, angle=math.radians(7)) is None


def test_a_run_that_ends_first_diverges_where_it_ended():
    a = record()
    cut = dataclasses.replace(a, samples=a.samples[:100], end={"status": "INCOMPLETE"})
    found = first_divergence(a, cut)
    assert found is not None
    assert found.time == a.samples[100]["t"]  # the first tick B does not have
    assert found.b.time == a.samples[99]["t"]
    assert found.reason == f"run B ended at {a.samples[99]['t']:.1f} s (INCOMPLETE), run A went on"


def test_differing_tick_rates_are_aligned_to_the_nearest_tick_and_said():
    found = first_divergence(record(), record(tick_hz="20"))
    assert found is not None
    assert "tick rates differ: 10 Hz in A, 20 Hz in B" in found.reason


def test_the_pose_source_follows_the_backend_the_log_names(tmp_path):
    recorder = Recorder(log_path=tmp_path / "run.jsonl")
    recorder.finish(Run(load_mission("square")).run(on_tick=recorder))
    logged = read_log(tmp_path / "run.jsonl")
    assert logged.header["backend"] == "sim" and pose_source(logged) == "ground truth"
    assert pose_source(dataclasses.replace(logged, header={**logged.header, "backend": "thymio"})) == "odometry"
    older = dataclasses.replace(logged, header={k: v for k, v in logged.header.items() if k != "backend"})
    assert pose_source(older) == "as logged"
    assert first_divergence(logged, older) is None  # the same run, whatever its header says
