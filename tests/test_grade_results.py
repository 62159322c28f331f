"""The grade's results as types (:mod:`thymio_bt.grade.results`): results.json written byte for
byte as before for a small class (tests/data/grade_golden/, graded by the code before the types),
read back into the same types and written again unchanged, and a results file or a run message
that is not the contract refused with a clear message."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.cli.app import json_text
from thymio_bt.grade.grader import grade
from thymio_bt.grade.results import ClassResults, GraderCode, StudentStatus
from thymio_bt.run.result import RunStatus

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = ROOT / "tests" / "data" / "grade_golden"
CLASS = ROOT / "examples" / "class"
STUDENTS = ("ada", "chen", "dana", "eve")


def graded_text(worlds: Path) -> str:
    """results.json of the golden class as the grader writes it, with what changes from machine to
    machine (the wall time, the repository's and the worlds' folders) put in words."""
    os.chdir(ROOT)  # the results name files relative to where the grade ran
    results = grade(
        GOLDEN.relative_to(ROOT) / "assignment.yaml",
        [CLASS.relative_to(ROOT) / name for name in STUDENTS],
        workers=2,
        worlds=worlds,
        relative_to=ROOT,
    )
    data = results.to_json()
    data["summary"]["wall_time"] = 0.0
    text = json_text(data)
    return (
        text.replace(os.path.relpath(worlds, ROOT), "WORLDS").replace(str(worlds), "WORLDS").replace(str(ROOT), "ROOT")
    )


def test_results_json_is_written_byte_for_byte_as_before(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # graded_text goes to the repository; monkeypatch comes back
    assert graded_text(tmp_path / "worlds") == (GOLDEN / "results.json").read_text()


if __name__ == "__main__":  # the golden file again, after a change to the contract made on purpose
    import tempfile

    (GOLDEN / "results.json").write_text(graded_text(Path(tempfile.mkdtemp(prefix="thymio-bt-golden-"))))


def test_results_json_read_back_is_written_again_byte_for_byte():
    text = (GOLDEN / "results.json").read_text()
    results = ClassResults.from_json(json.loads(text))
    assert json_text(results.to_json()) == text
    chen = next(s for s in results.students if s.name == "chen")
    assert chen.status is StudentStatus.GRADED and chen.palette[0].points == 1.5 and chen.penalty == -1.5
    assert {type(r.status) for s in results.students for r in s.runs} == {RunStatus}
    eve = next(s for s in results.students if s.name == "eve")
    assert eve.status is StudentStatus.INVALID and eve.runs == [] and eve.score == 0


@pytest.mark.parametrize(
    ("change", "said"),
    [
        (lambda r: r["students"][0].update(status="passed"), "students.0.status: Input should be 'graded'"),
        (lambda r: r["students"][0].update(score="10"), "students.0.score: Input should be a valid number"),
        (lambda r: r["students"][0]["runs"][0].update(bonus=5), "students.0.runs.0.bonus: unknown key 'bonus'"),
        (lambda r: r["students"][1].pop("max"), "students.1.max: missing required key 'max'"),
        (lambda r: r.update(students={}), "students: Input should be a valid array"),
    ],
)
def test_update_refuses_results_that_are_not_the_contract_saying_where(tmp_path, change, said):
    results = json.loads((GOLDEN / "results.json").read_text())
    change(results)
    old = tmp_path / "old.json"
    old.write_text(json.dumps(results))
    result = CliRunner().invoke(
        main, ["grade", str(GOLDEN / "assignment.yaml"), str(CLASS / "ada"), "--update", str(old)]
    )
    assert result.exit_code == 2 and said in result.output and "Traceback" not in result.output, result.output
    assert result.output.startswith(f"error: --update {old}: not results.json: ")


#: what a child's pipe may carry instead of a run: (what the forged message is, the JSON line)
FORGED = {
    "a variant the task does not have": {"variant": "nowhere"},
    "a key results.json does not have": {"score": 100.0},
    "a status no run ends with": {"status": "PASSED"},
    "a criterion the world is not judged by": {"criteria": {"bonus": {"passed": True}}},
}


def test_forged_run_messages_neither_crash_the_grader_nor_earn_a_point(tmp_path, monkeypatch):
    """A child's pipe is read as strictly as a file: every run below is forged (each criterion
    passed, and something else the grader did not send), or not a message at all; each is a crash
    of its run, the others are graded, and the forged runs earn nothing."""
    lines = [
        *({"kind": "run", **_honest_run(i), **forged} for i, forged in enumerate(FORGED.values())),
        [1, 2],  # JSON, not an object
        "not JSON",
    ]

    def forge(task, send, skip=0):
        for index in range(skip, task.runs):
            send({"kind": "start", "index": index})
            line = lines[index]
            if line == "not JSON":  # written on the pipe itself, as a child's own code could
                pipe = next(c.cell_contents for c in send.__closure__ if isinstance(c.cell_contents, int))
                os.write(pipe, b"not JSON\n")
                continue
            send(line if not isinstance(line, dict) else line | {"index": index})

    monkeypatch.setattr("thymio_bt.grade.grader.grade_runs", forge)
    assignment = tmp_path / "forged.yaml"
    assignment.write_text(
        "name: forged\nvariants:\n  - {name: course, maze: two_parts_maze, start: part1, noise: off, seeds: 6}\n"
        "criteria:\n  - {name: ends by itself, points: 1, finishes: true}\n"
    )
    results = grade(assignment, [CLASS / "ada"], workers=1)
    (ada,) = results.students
    assert ada.score == 0 and [c.earned for c in ada.criteria] == [0.0]
    assert [r.code for r in ada.runs] == [GraderCode.CRASH] * 6
    assert all(not j.passed for r in ada.runs for j in r.criteria.values())
    assert all(set(r.criteria) == {"ends by itself"} for r in ada.runs)
    assert "sent" in (ada.runs[0].reason or "") and "score" not in results.to_json()["students"][0]["runs"][1]


def _honest_run(index: int) -> dict[str, object]:
    """A run message as a child sends it, every criterion passed."""
    return {
        "index": index,
        "variant": "course",
        "seed": index,
        "robot": "course",
        "status": "SUCCESS",
        "criteria": {"ends by itself": {"passed": True, "feedback": None, "moment": None, "where": None}},
    }
