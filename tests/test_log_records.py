"""What a log holds is declared once: every key of a run's recording, and of a log of each format read
back (whole, damaged, without poses), is a key of its TypedDict (``LogHeader``, ``TickRecord``,
``LogEnd``, ``TreeNode``), which ``Recording`` is typed with; a pose as a dict is named apart from
``RunResult.final_pose``, a ``Pose``."""

import dataclasses

import pytest

from thymio_bt.btcpp.btlog import read_btlog
from thymio_bt.logs import read_log
from thymio_bt.logs.entries import LogEnd, LogHeader, Recording, TickRecord, TreeNode
from thymio_bt.logs.jsonl import read_jsonl
from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.run.runner import Run


def keys(record: type) -> set[str]:
    """The keys a TypedDict declares, required or not."""
    return set(record.__required_keys__ | record.__optional_keys__)


def undeclared(recording: Recording) -> dict[str, set[str]]:
    """The keys ``recording`` holds that its TypedDicts do not declare, by record."""
    found = {
        "header": set(recording.header) - keys(LogHeader),
        "tick": {k for s in recording.samples for k in s} - keys(TickRecord),
        "end": set(recording.end) - keys(LogEnd),
        "tree": {k for n in recording.header.get("tree", []) for k in n} - keys(TreeNode),
    }
    return {record: extra for record, extra in found.items() if extra}


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """A run of ``square`` (its map made up: square maps nothing) in memory, and logged in each format."""
    folder = tmp_path_factory.mktemp("logs")
    for suffix in ("jsonl", "mcap", "btlog"):
        recorder = Recorder(log_path=folder / f"run.{suffix}")
        result = Run(load_mission("square")).run(on_tick=recorder)
        recording = recorder.finish(dataclasses.replace(result, maze_map={"cells": [[0, 0]]}))
    return folder, result, recording


def test_a_runs_recording_holds_only_declared_keys(logs):
    _, result, recording = logs
    assert "map" in recording.end
    assert undeclared(recording) == {}
    # one name, one type: the result's final_pose is a Pose, the recording's dict form final_pose_json
    assert isinstance(result.final_pose, Pose)
    assert recording.final_pose_json == result.final_pose.as_dict()


@pytest.mark.parametrize("suffix", ["jsonl", "mcap", "btlog"])
def test_a_log_read_back_holds_only_declared_keys(logs, suffix):
    folder, _, _ = logs
    recording = read_log(folder / f"run.{suffix}")
    assert recording.samples and recording.end
    assert undeclared(recording) == {}


def test_a_damaged_log_read_in_part_holds_only_declared_keys(logs, tmp_path):
    folder, _, _ = logs
    lines = (folder / "run.jsonl").read_text().splitlines()
    (tmp_path / "cut.jsonl").write_text("\n".join([*lines[:50], '{"kind": "tick"}', *lines[51:]]))
    data = (folder / "run.btlog").read_bytes()
    (tmp_path / "cut.btlog").write_bytes(data[:-5])
    for recording in (read_jsonl(tmp_path / "cut.jsonl", partial=True), read_btlog(tmp_path / "cut.btlog")):
        assert "damaged_at" in recording.header
        assert undeclared(recording) == {}


def test_a_recording_is_typed_with_the_log_records():
    hints = Recording.__annotations__  # as written (the module's annotations are postponed)
    assert (hints["samples"], hints["end"], hints["header"]) == ("list[TickRecord]", "LogEnd", "LogHeader")
    assert not hasattr(Recording, "final_pose")  # a dict under the name a RunResult keeps a Pose under
