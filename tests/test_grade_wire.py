"""The tick frames between the grader and a submission's confined process (:mod:`thymio_bt.grade.wire`):
exact both ways, and a reply from the submission read as untrusted; confined grading gives the
example class the very grades unconfined grading does."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from thymio_bt.grade.grader import grade
from thymio_bt.grade.wire import (
    DRIVE,
    OBSERVATION,
    REPLY,
    WireError,
    observation_frame,
    read_observation,
    read_reply,
    reply_frame,
)

ROOT = Path(__file__).resolve().parent.parent


def test_an_observation_arrives_bit_for_bit():
    head = (12.3, True, True, False, 0.1 + 0.2, -0.0, math.pi)  # clock, flags, odometry
    values = (*head, *[1 / 3, math.inf] * 3, 5e-324, -1e308, 0.0, 2.5, -7.0, 2**40)  # ranges, twists, collisions
    frame = observation_frame(values, [[3, "failed", "an entity named 'thymio' already exists"]])
    got, served = read_observation(frame)
    assert got == values and [math.copysign(1, v) for v in got[4:7]] == [1, -1, 1]
    assert served == [[3, "failed", "an entity named 'thymio' already exists"]]
    assert read_observation(observation_frame(values, []))[1] == []


def test_a_reply_keeps_every_drive_command_and_the_rest():
    drives = [(0.1, -0.0), (1 / 3, 2e-300)]
    rest = {"q": [[0, "delete", "thymio", 0.0, 0.0, 0.0]], "ev": [{"t": 0.1, "kind": "x"}], "tip": "root/A"}
    assert read_reply(reply_frame("SUCCESS", drives, rest)) == ("SUCCESS", drives, rest)
    assert read_reply(reply_frame("INVALID", [], {"x": "the run raised ValueError"}))[0] == "INVALID"


HEAD = REPLY.pack(b"R", 1, 1)


@pytest.mark.parametrize(
    ("frame", "said"),
    [
        (b"R", "too short"),
        (REPLY.pack(b"O", 1, 0), "wrong shape"),  # an observation's tag
        (REPLY.pack(b"R", 4, 0), "wrong shape"),  # no such status
        (REPLY.pack(b"R", 1, 3) + DRIVE.pack(0.1, 0.0), "wrong shape"),  # fewer drives than it says
        (REPLY.pack(b"R", 1, 65535), "wrong shape"),
        (HEAD + DRIVE.pack(math.nan, 0.0), "not two finite numbers"),
        (HEAD + DRIVE.pack(0.1, -math.inf), "not two finite numbers"),
        (HEAD + DRIVE.pack(0.1, 0.0) + b"[1, 2]", "not a JSON object"),
        (HEAD + DRIVE.pack(0.1, 0.0) + b"\x00garbage", "not JSON"),
        (HEAD + DRIVE.pack(0.1, 0.0) + b"[" * 100_000, "not JSON"),
        (json.dumps({"st": "SUCCESS", "d": [[0.1, 0.0]]}).encode(), "wrong shape"),  # the old JSON reply
    ],
)
def test_a_reply_of_another_shape_is_refused(frame, said):
    with pytest.raises(WireError, match=said):
        read_reply(frame)


def test_the_frames_are_the_sizes_the_docs_say():
    assert OBSERVATION.size == 1 + 8 + 3 + 8 * (3 + 7 + 4) + 8 and REPLY.size == 4 and DRIVE.size == 16


def _runs(results: dict) -> dict:
    """Each student's runs as graded, without the wall-clock time they took."""
    return {s["name"]: (s["score"], s["runs"]) for s in results["students"]}


def test_confined_grading_gives_the_example_class_the_same_grades_bit_for_bit(tmp_path):
    subs = tmp_path / "subs"
    shutil.copytree(ROOT / "examples" / "class", subs)
    assignment = ROOT / "assignments" / "course_part1_2.yaml"
    text = assignment.read_text().replace("plugins: false", "plugins: true")
    text = text.replace("maze: ../mazes/", f"maze: {ROOT}/mazes/")
    text = text.replace("maze: worlds/", f"maze: {ROOT}/assignments/worlds/")
    allowed = tmp_path / "allowed.yaml"
    allowed.write_text(text)
    inside = grade(allowed, sorted(subs.iterdir()), workers=2, worlds=tmp_path / "w", sandbox="always").to_json()
    outside = grade(allowed, sorted(subs.iterdir()), workers=2, worlds=tmp_path / "w").to_json()
    assert inside["summary"]["confinement"].startswith("confined")
    assert sum(len(runs) for _, runs in _runs(inside).values()) > 40
    assert _runs(inside) == _runs(outside)
