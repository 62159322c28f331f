"""Regrading some students into earlier results (--update), and the submissions that are the same
tree under other names and numbers (similar)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from click.testing import CliRunner

from thymio_bt.cli import main

ROOT = Path(__file__).resolve().parent.parent
CLASS = ROOT / "examples" / "class"
ASSIGNMENT = """\
name: part1
submission: part1_2.yaml
variants:
  - {name: course, maze: two_parts_maze, start: part1, noise: off}
criteria:
  - {name: part 1 stops 5 cm from the wall, points: 2, gap: {at: delete, distance: 5cm, tolerance: 5mm}}
  - {name: ends by itself, points: 1, finishes: true}
"""
#: ada's tree with every name, comment, number and the layout changed: the same tree
DISGUISED = """
name: mine
maze: two_parts_maze
start: part1
tree:
  sequence:
    name: everything
    children:
      - {MoveUntilWall: {name: first, speed: 9cm/s, distance: 4.8cm}}
      - DeleteEntity: {entity: thymio}
      - SpawnEntity: {entity: thymio, pose: [0.5, 0.3, 90deg]}
      - repeat:
          name: loop
          until: IsDeadEnd
          do:
            sequence:
              name: leg
              children:
                - parallel: {name: both, policy: success_on_all, children: [
                    MoveUntilWall: {speed: 11cm/s, distance: 4.9cm, centre: true}, ChooseTurn: {}]}
                - selector:
                    name: which
                    children:
                      - IsDeadEnd
                      - sequence: {name: t, children: [MoveUntilWall: {distance: 2cm}, TurnAngle: {angle: 90deg}]}
"""


def _student(subs: Path, name: str, text: str) -> Path:
    (subs / name).mkdir(parents=True, exist_ok=True)
    (subs / name / "part1_2.yaml").write_text(text)
    return subs / name


def test_update_regrades_the_named_students_keeps_the_others_and_writes_the_site_whole(tmp_path):
    assignment = tmp_path / "a.yaml"
    assignment.write_text(ASSIGNMENT)
    subs = tmp_path / "subs"
    ada = _student(subs, "ada", (CLASS / "ada" / "part1_2.yaml").read_text())
    dana = _student(subs, "dana", (CLASS / "dana" / "part1_2.yaml").read_text())
    out, site = tmp_path / "results.json", tmp_path / "site"
    first = CliRunner().invoke(
        main, ["grade", str(assignment), str(ada), str(dana), "--out", str(out), "--html", str(site)]
    )
    assert first.exit_code == 0, first.output
    before = json.loads(out.read_text())
    assert [s["score"] for s in before["students"]] == [3, 1]
    (site / "students" / "gone.html").write_text("a page of a student no longer in the results")
    shutil.copy(CLASS / "ada" / "part1_2.yaml", dana / "part1_2.yaml")  # dana hands in again, fixed
    again = CliRunner().invoke(main, ["grade", str(assignment), str(dana), "--update", str(out), "--html", str(site)])
    assert again.exit_code == 0, again.output
    after = json.loads(out.read_text())
    assert [(s["name"], s["score"]) for s in after["students"]] == [("ada", 3), ("dana", 3)]
    assert after["students"][0] == before["students"][0]  # ada was not run again
    assert after["summary"]["students"] == 2 and after["summary"]["mean_score"] == 3
    assert after["summary"]["runs"] == 2
    assert sorted(p.name for p in (site / "students").iterdir()) == ["ada.html", "dana.html"]
    index = (site / "index.html").read_text()
    assert 'href="students/ada.html"' in index and 'href="students/dana.html"' in index
    assert 'id="score">3 <small>/ 3</small>' in (site / "students" / "dana.html").read_text()


def test_update_refuses_results_of_another_assignment(tmp_path):
    old = tmp_path / "old.json"
    old.write_text(json.dumps({"assignment": {"name": "another"}, "students": []}))
    result = CliRunner().invoke(main, ["grade", "course_part1_2", str(CLASS / "ada"), "--update", str(old)])
    assert result.exit_code == 2 and "those results are of assignment 'another'" in result.output


def test_trees_equal_up_to_names_comments_layout_and_values_are_grouped_for_the_ta(tmp_path):
    assignment = tmp_path / "a.yaml"
    assignment.write_text(ASSIGNMENT)
    subs = tmp_path / "subs"
    folders = [
        _student(subs, "ada", (CLASS / "ada" / "part1_2.yaml").read_text()),
        _student(subs, "bob", (CLASS / "bob" / "part1_2.yaml").read_text()),
        _student(subs, "copycat", DISGUISED),
        _student(subs, "chen", (CLASS / "chen" / "part1_2.yaml").read_text()),
    ]
    out, site = tmp_path / "r.json", tmp_path / "site"
    result = CliRunner().invoke(
        main, ["grade", str(assignment), *map(str, folders), "--out", str(out), "--html", str(site)]
    )
    assert result.exit_code == 0, result.output
    results = json.loads(out.read_text())
    assert results["similar"] == [["ada", "copycat"]]
    index = (site / "index.html").read_text()
    assert '<ul id="similar"><li><a href="students/ada.html">ada</a>, <a href="students/copycat.html">copycat</a>' in (
        index
    )
    students = tmp_path / "students"
    result = CliRunner().invoke(
        main, ["grade", str(assignment), *map(str, folders), "--html", str(students), "--for-students"]
    )
    assert result.exit_code == 0 and "Similar trees" not in (students / "index.html").read_text()
