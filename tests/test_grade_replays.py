"""``grade --html``: each failed run a student's page lists first (per variant and mistake) links to
its replay, the viewer's page opened at the failing moment with the verdicts on its timeline; a site
for students never replays a hidden variant. Checked on real gradings, in headless Chromium."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import _require
import pytest
from click.testing import CliRunner
from test_grade_site import Page

from thymio_bt.cli import main
from thymio_bt.grade.confine import plan
from thymio_bt.grade.grader import grade
from thymio_bt.grade.results import RunMessage
from thymio_bt.grade.site_replay import failing_moment, went_wrong
from thymio_bt.grade.student import StudentTask, grade_runs
from thymio_bt.grade.worlds import load_worlds

ROOT = Path(__file__).resolve().parent.parent
PART12 = ROOT / "assignments" / "course_part1_2.yaml"
DANA = ROOT / "examples" / "class" / "dana" / "part1_2.yaml"  # stops too far from the wall: fails
HIDDEN = """\
name: hidden_worlds
submission: part1_2.yaml
variants:
  - {name: course, maze: two_parts_maze, start: part1, seeds: 1, noise: off}
  - {name: secret_box, maze: ASSIGNMENTS/worlds/part12_long_part1.yaml, start: [0.18, 0.1, 0], visibility: hidden,
     noise: off}
"""
CRITERIA = """\
criteria:
  - {name: part 1 stops 5 cm from the wall, points: 2, gap: {at: delete, distance: 5cm, tolerance: 5mm}}
"""


def _grade(tmp_path: Path, assignment: Path, *options: str) -> tuple[Path, dict[str, Any]]:
    """Grade dana alone with ``--html``; the site and results.json."""
    (sub := tmp_path / "subs" / "dana").mkdir(parents=True, exist_ok=True)
    (sub / "part1_2.yaml").write_text(DANA.read_text())
    site, out = tmp_path / "site", tmp_path / "results.json"
    args = ["grade", str(assignment), str(sub), "--html", str(site), "--out", str(out), "--workers", "1", *options]
    result = CliRunner().invoke(main, args)
    assert result.exit_code in (0, 1), result.output
    return site, json.loads(out.read_text())


def _hidden(tmp_path: Path) -> Path:
    path = tmp_path / "hidden.yaml"
    path.write_text((HIDDEN + CRITERIA).replace("ASSIGNMENTS", str(PART12.parent)))
    return path


def test_only_the_first_run_of_each_mistake_is_recorded_and_only_when_asked(tmp_path):
    assignment, worlds = load_worlds(PART12, tmp_path)
    course = next(w for w in worlds if w.name == "course")
    course.seeds = [0, 1]
    sent: dict[bool, list[dict[str, Any]]] = {}
    for asked in (False, True):
        task = StudentTask("dana", str(DANA), [course], assignment.criteria, replays=["course"] if asked else [])
        sent[asked] = [m for m in _messages(task) if m["kind"] == "run"]
    assert all("replay" not in m for m in sent[False])  # no --html: nothing recorded
    first, second = sent[True]
    assert went_wrong(_run(first)) and went_wrong(_run(second)) == went_wrong(_run(first))  # the same mistakes twice
    assert "replay" in first and "replay" not in second
    replay = first["replay"]
    assert replay["failing"] == round(failing_moment(_run(first)), 3)
    verdicts = [e for e in replay["events"] if e["kind"] == "verdict"]
    assert [e["name"] for e in verdicts] == [m for m in went_wrong(_run(first)) if m != "ended"]
    # the replay is the graded run: it ends where the graded run ended
    assert replay["end"]["final_pose"] == first["final_pose"] and replay["t"][-1] == pytest.approx(first["sim_time"])
    without = {k: v for k, v in first.items() if k != "replay"}
    assert without == sent[False][0]  # recording changes nothing of the graded run


def _run(message: dict[str, Any]) -> RunMessage:
    """A run's message (or a run of results.json) read back."""
    return RunMessage.from_json({k: v for k, v in message.items() if k != "kind"})


def _messages(task: StudentTask) -> list[dict[str, Any]]:
    messages: list[dict[str, Any]] = []
    grade_runs(task, messages.append)
    return messages


def test_a_failed_run_links_to_its_replay_at_the_failing_moment(browser, tmp_path):
    site, results = _grade(tmp_path, PART12)
    assert "replay" not in json.dumps(results)  # results.json stays as it was
    page = site / "students" / "dana.html"
    links = [a["href"] for tag, a in Page(page).tags if tag == "a" and "replay" in (a.get("class") or "")]
    runs = {r["index"]: r for r in results["students"][0]["runs"]}
    assert len(links) == len(list((site / "replays").glob("*.html"))) >= 4  # one a variant at least
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    href = tab.evaluate("document.querySelector('a.replay').href")
    tab.close()
    first = next(r for r in runs.values() if went_wrong(_run(r)))  # the first failed run is the first link
    moment = failing_moment(_run(first))
    assert href.endswith(f"#t={moment:g}") and f"dana_{first['variant']}_seed{first['seed']}" in href
    replay = browser.open(href)
    shown = replay.evaluate(
        "({time: +document.querySelector('[data-time]').dataset.time,"
        " verdicts: [...document.querySelectorAll('rect.mark.verdict')].map(m => m.textContent),"
        " nodes: document.querySelectorAll('[data-node]').length})"
    )
    assert replay.problems() == []
    replay.close()
    assert moment - 0.1 < shown["time"] <= moment + 1e-6  # the tick at (or just before) the failing moment
    missed = [m for m in went_wrong(_run(first)) if m != "ended"]
    assert len(shown["verdicts"]) == len(missed) and all(
        any(name in text for text in shown["verdicts"]) for name in missed
    )
    assert shown["nodes"] > 10


def test_a_site_for_students_never_replays_a_hidden_variant(browser, tmp_path, monkeypatch):
    assignment = _hidden(tmp_path)
    ta_site, ta = _grade(tmp_path / "ta", assignment)
    by_variant = {r["variant"]: r for r in ta["students"][0]["runs"]}
    assert went_wrong(_run(by_variant["secret_box"])) and went_wrong(_run(by_variant["course"]))  # both failed
    assert sorted(p.name for p in (ta_site / "replays").iterdir()) == [
        "dana_course_seed0.html",
        "dana_secret_box_seed0.html",
    ]
    site, _ = _grade(tmp_path / "students", assignment, "--for-students")
    assert sorted(p.name for p in (site / "replays").iterdir()) == ["dana_course_seed0.html"]
    page = site / "students" / "dana.html"
    links = [a["href"] for tag, a in Page(page).tags if tag == "a" and "replay" in (a.get("class") or "")]
    assert len(links) == 1 and links[0].startswith("../replays/dana_course_seed0.html#t=")
    assert "secret_box" not in "".join(p.read_text() for p in site.rglob("*.html"))
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    tab.close()


@pytest.mark.skipif(
    (not sys.platform.startswith("linux") or plan().missing != {}) and not _require.REQUIRE_ALL,
    reason="needs Landlock ABI 6+ (in CI, THYMIO_BT_REQUIRE_ALL=1, its absence fails)",
)
def test_a_confined_submissions_replay_is_made_again_in_its_confined_process(tmp_path):
    """A submission whose tree ticks in a confined process (every one, with ``sandbox="always"``) is
    replayed from a run made again there: it ends where the graded run ended."""
    assignment = tmp_path / "confined.yaml"
    assignment.write_text(HIDDEN.split("  - {name: secret_box")[0] + CRITERIA + "palette: {plugins: true}\n")
    (sub := tmp_path / "subs" / "dana").mkdir(parents=True)
    (sub / "part1_2.yaml").write_text(DANA.read_text())
    results = grade(assignment, [sub], workers=1, sandbox="always", replays="all").to_json()
    assert results["summary"]["confinement"].startswith("confined")
    first, *_ = results["students"][0]["runs"]
    assert "replay" in first and went_wrong(_run(first))
    assert first["replay"]["end"]["final_pose"] == first["final_pose"]
    assert first["replay"]["failing"] == round(failing_moment(_run(first)), 3)
    # the tree as it ticked in the confined process, node by node, as in a run ticked in the grader
    # (before: one node, the grader's stand-in root, and no statuses of the submission's tree)
    (here,) = grade(assignment, [sub], workers=1, replays="all").to_json()["students"][0]["runs"][:1]
    assert len(first["replay"]["tree"]) == len(here["replay"]["tree"]) == 15
    assert first["replay"]["tree"] == here["replay"]["tree"]
    assert first["replay"]["status"] == here["replay"]["status"]
