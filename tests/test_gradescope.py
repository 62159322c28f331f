"""Gradescope's autograder: examples/gradescope/run_autograder run against an /autograder-shaped
folder, as Gradescope runs it for one submission, writes a results.json in Gradescope's format
whose hidden worlds say nothing before the due date."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "gradescope"
ASSIGNMENT = """\
name: stop_at_wall
submission: part1_2.yaml
variants:
  - {name: course, maze: two_parts_maze, start: part1, noise: off}
  - {name: secret_corridor, generate: {kind: path, length: 5, seed: secret, turns: left}, visibility: hidden,
     noise: off}
criteria:
  - {name: stops 5 cm from the wall, points: 2, gap: {at: delete, distance: 5cm, tolerance: 5mm}, variants: [course]}
  - {name: never touches a wall, points: 2, no_collision: true}
  - {name: ends by itself, points: 1, finishes: true}
palette: {forbid: [WallFollow], penalty: 1}
"""
VISIBILITY = {"hidden", "after_due_date", "after_published", "visible"}


def _autograder(tmp_path: Path, student: str, assignment: str = ASSIGNMENT) -> tuple[Path, subprocess.CompletedProcess]:
    root = tmp_path / "autograder"
    shutil.copytree(EXAMPLE, root / "source")
    (root / "source" / "assignment.yaml").write_text(assignment)
    (root / "source" / "secret.txt").write_text("the course's secret\n")
    (root / "submission").mkdir(parents=True)
    shutil.copy(ROOT / "examples" / "class" / student / "part1_2.yaml", root / "submission")
    env = {
        **os.environ,
        "AUTOGRADER_ROOT": str(root),
        "THYMIO_BT": str(Path(sys.executable).parent / "thymio-bt"),
    }
    env.pop("THYMIO_BT_SECRET", None)
    done = subprocess.run(
        ["bash", str(root / "source" / "run_autograder")], env=env, cwd=tmp_path, capture_output=True, text=True
    )
    return root, done


@pytest.mark.parametrize("student", ["dana", "chen"])
def test_run_autograder_writes_gradescope_s_results_for_one_submission(tmp_path, student):
    root, done = _autograder(tmp_path, student)
    assert done.returncode == 0, done.stderr
    results = json.loads((root / "results" / "results.json").read_text())
    assert set(results) == {"score", "output", "tests"}
    for test in results["tests"]:
        assert set(test) == {"name", "score", "max_score", "status", "output", "visibility"}
        assert test["status"] in ("passed", "failed") and test["visibility"] in VISIBILITY
        assert test["score"] <= test["max_score"]
    by_name = {t["name"]: t for t in results["tests"]}
    assert by_name["never touches a wall"]["visibility"] == "visible"
    assert by_name["never touches a wall (hidden worlds)"]["visibility"] == "after_due_date"
    assert by_name["never touches a wall"]["max_score"] == by_name["never touches a wall (hidden worlds)"]["max_score"]
    assert "stops 5 cm from the wall (hidden worlds)" not in by_name  # it judges the course's world only
    text = json.dumps(results)
    assert "secret_corridor" not in text and "thymio-bt run" not in text and "the course's secret" not in text
    if student == "dana":  # stops 7 cm from the wall
        stop = by_name["stops 5 cm from the wall"]
        assert (stop["score"], stop["max_score"], stop["status"]) == (0, 2, "failed")
        assert stop["output"].startswith("course: stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm (at ")
        assert results["score"] == sum(t["score"] for t in results["tests"])
    else:  # WallFollow is forbidden: the penalty is a test of its own
        palette = by_name["palette"]
        assert palette["score"] == -1 and "WallFollow is not allowed" in palette["output"]


def test_run_autograder_fails_on_a_bad_assignment(tmp_path):
    root, done = _autograder(tmp_path, "ada", ASSIGNMENT.replace("points: 2, no_collision", "points: -2, no_collision"))
    assert done.returncode == 2 and "Input should be greater than 0" in done.stderr
    assert not (root / "results" / "results.json").exists()


def test_gradescope_grades_one_submission(tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    subs = [str(ROOT / "examples" / "class" / n) for n in ("ada", "bob")]
    result = CliRunner().invoke(main, ["grade", "course_part1_2", *subs, "--gradescope", str(tmp_path / "g.json")])
    assert result.exit_code == 2 and "--gradescope grades one submission, got 2" in result.output
