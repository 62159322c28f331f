"""What the student page draws: a respawn as a jump (from the run's spawn events, however sparse
its samples), a run's end said once, the tree as a tree."""

from __future__ import annotations

import json
from pathlib import Path

from thymio_bt.grade.site_student import student_page, tree_guides
from thymio_bt.grade.site_svg import split_jumps, trajectory_svg

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "tests" / "data" / "grade_results_sample.json"

#: a run sampled every 0.5 s: the respawn moves 20 cm in one interval, slower than any speed rule
#: would call a jump, and a fast drive after it is no respawn
SPARSE = [(0.0, 0.40, 0.10), (0.5, 0.49, 0.10), (1.0, 0.50, 0.30), (1.5, 0.50, 0.62)]


def test_a_respawn_is_drawn_as_a_jump_from_the_events_not_from_the_speed():
    assert split_jumps(SPARSE, spawns=[0.8]) == [[(0.40, 0.10), (0.49, 0.10)], [(0.50, 0.30), (0.50, 0.62)]]
    assert len(split_jumps(SPARSE, spawns=[])) == 1  # 64 cm/s, but no spawn: a path
    run = {
        "status": "SUCCESS",
        "criteria": {},
        "seed": 0,
        "spawns": [0.8],
        "final_pose": {"x": 0.5, "y": 0.62, "yaw": 1.57},
        "trajectory": [[t, x, y, 0.0] for t, x, y in SPARSE],
    }
    svg, _ = trajectory_svg(None, {"name": "course"}, [run])
    assert svg.count('class="jump"') == 1 and svg.count("<polyline") == 2


def test_a_timed_out_run_says_timeout_once():
    results = json.loads(SAMPLE.read_text())
    student = results["students"][1]
    student["runs"][0] |= {"status": "TIMEOUT", "code": "TIMEOUT", "reason": "did not end within 120 s"}
    page = student_page(results, student, {})
    assert "TIMEOUT TIMEOUT" not in page and "TIMEOUT" in page


def test_the_tree_is_drawn_as_a_tree():
    assert tree_guides([0, 1, 1, 2, 3, 2, 1]) == ["", "├─ ", "├─ ", "│  ├─ ", "│  │  └─ ", "│  └─ ", "└─ "]
    results = json.loads(SAMPLE.read_text())
    student = results["students"][0]
    page = student_page(results, student, {})
    nodes = student["coverage"]["nodes"]
    assert page.count('<span class="guide" aria-hidden="true">') == len(nodes)
    assert "└─ " in page and "padding-left" not in page.split('id="coverage"')[1]
