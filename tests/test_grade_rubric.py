"""Rubrics that measure what they say: each criterion judged on the phase it is about, the real
cause named, a cruise speed, credit shared over variants, palette names checked, penalties visible
in every report, blame on the node that set the distance, an assignment's problems in one round."""

from __future__ import annotations

import csv
import io
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.grade.assignment import Criterion, load_assignment
from thymio_bt.grade.checks import RunFacts, judge, turns_said
from thymio_bt.grade.grader import grade
from thymio_bt.grade.reports import gradebook_csv, junit_xml
from thymio_bt.maze.generate import path_maze
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import robot_model
from thymio_bt.run.result import RunStatus

ROOT = Path(__file__).resolve().parent.parent
PART12 = ROOT / "assignments" / "course_part1_2.yaml"
CLASS = ROOT / "examples" / "class"
ADA = (CLASS / "ada" / "part1_2.yaml").read_text()
DELETE_THEN_SPAWN = (
    "      - DeleteEntity: {entity: thymio}\n      - SpawnEntity: {entity: thymio, pose: [0.5, 0.3, pi/2]}\n"
)
ONE_NODE = "name: x\nmaze: two_parts_maze\nstart: part1\ntree:\n  MoveUntilWall: {speed: 10cm/s, distance: 5cm}\n"


def _folders(tmp: Path, files: dict[str, str]) -> list[Path]:
    out = []
    for name, text in files.items():
        (tmp / name).mkdir(parents=True)
        (tmp / name / "part1_2.yaml").write_text(text)
        out.append(tmp / name)
    return out


def _criteria(student: dict) -> dict[str, dict]:
    return {c["name"]: c for c in student["criteria"]}


@pytest.fixture(scope="module")
def gamed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict]:
    """The shipped part 1-2 assignment on the submissions that gamed its rubric."""
    assert DELETE_THEN_SPAWN in ADA
    spawn_first = ADA.replace(
        DELETE_THEN_SPAWN,
        "      - SpawnEntity: {entity: thymio, pose: [0.5, 0.3, pi/2]}\n      - DeleteEntity: {entity: thymio}\n",
    )
    folders = _folders(
        tmp_path_factory.mktemp("gamed"),
        {"one_node": ONE_NODE, "spawn_first": spawn_first, "twice_as_fast": ADA.replace("10cm/s", "20cm/s")},
    )
    return {s["name"]: s for s in grade(PART12, folders, workers=2).to_json()["students"]}


PART_1 = {"part 1 stops 5 cm from the wall", "part 1 drives at 10 cm/s"}
PART_2 = {
    "respawns only after the delete completed",
    "respawns at (0.5, 0.3, yaw pi/2)",
    "part 2 turns left at each wall",
    "stops at the dead end, 5 cm from its wall",
}


def test_the_one_node_mission_earns_part_1_and_nothing_of_part_2(gamed):
    criteria = _criteria(gamed["one_node"])
    assert all(criteria[name]["passed"] for name in PART_1)
    assert all(criteria[name]["earned"] == 0 for name in PART_2)
    dead_end = criteria["stops at the dead end, 5 cm from its wall"]
    assert dead_end["feedback"].startswith("ended before the dead end: took none of the 4 turns on the way there")


def test_spawn_before_delete_is_named_at_the_order_criterion(gamed):
    criteria = _criteria(gamed["spawn_first"])
    order = criteria["respawns only after the delete completed"]
    assert order["feedback"].startswith("the tree failed before any delete: an entity named 'thymio' already exists")
    assert order["where"].endswith("spawn_first/part1_2.yaml:12")  # the SpawnEntity
    assert criteria["stops at the dead end, 5 cm from its wall"]["earned"] == 0  # no dead end at part 1's wall
    assert criteria["part 1 stops 5 cm from the wall"]["passed"]


def test_twice_the_asked_speed_loses_the_speed_criterion_only(gamed):
    student = gamed["twice_as_fast"]
    missed = {c["name"]: c for c in student["criteria"] if not c["passed"]}
    assert list(missed) == ["part 1 drives at 10 cm/s"]
    assert missed["part 1 drives at 10 cm/s"]["feedback"].startswith(
        "drove at 20.0 cm/s before the delete, wanted 10 +- 1.5 cm/s (variant course"
    )
    assert missed["part 1 drives at 10 cm/s"]["where"].endswith("twice_as_fast/part1_2.yaml:11")
    assert student["score"] == student["max"] - 1


def _two_worlds(tmp_path: Path, credit: str) -> Path:
    assignment = tmp_path / f"{credit}.yaml"
    assignment.write_text(
        "name: a\nvariants:\n"
        f"  - {{name: course, maze: {ROOT}/thymio_bt/data/mazes/two_parts_maze.yaml, start: part1, noise: off}}\n"
        f"  - {{name: long, maze: {ROOT}/assignments/worlds/part12_long_part1.yaml, start: part1, noise: off}}\n"
        "criteria:\n"
        f"  - {{name: part 1 stop, points: 2, credit: {credit}, gap: {{at: delete, distance: 5cm}}}}\n"
    )
    return assignment


@pytest.mark.parametrize(("credit", "earned", "course"), [("shared", 1.0, 1.0), ("all", 0.0, 0.0)])
def test_credit_is_shared_over_variants_unless_all_or_nothing_is_asked(tmp_path, credit, earned, course):
    blind = CLASS / "bob"  # drives part 1 by odometry: right on the course's maze only
    (student,) = grade(_two_worlds(tmp_path, credit), [blind], workers=1).to_json()["students"]
    (criterion,) = student["criteria"]
    assert criterion["earned"] == student["score"] == earned
    assert [(v["name"], v["passed"], v["earned"]) for v in criterion["variants"]] == [
        ("course", True, course),
        ("long", False, 0.0),
    ]


def test_turn_feedback_reads_like_a_person_wrote_it():
    assert turns_said("", "LLLL") == "took no turn, wanted 4 left turns"
    assert turns_said("L", "LR") == "took 1 left turn, then no more: wanted 2 turns (left, right)"
    assert "never" not in turns_said("", "LLLL") and "0 turns" not in turns_said("", "LLLL")


def test_a_misspelt_palette_name_is_refused_with_did_you_mean_and_its_place(tmp_path):
    bad = tmp_path / "a.yaml"
    bad.write_text(PART12.read_text().replace("forbid: [WallFollow, GoToPose", "forbid: [WallFolow, GoToPose"))
    bad.with_name("worlds").symlink_to(PART12.parent / "worlds")
    line = next(n for n, text in enumerate(bad.read_text().splitlines(), 1) if "WallFolow" in text)
    for command in (["validate", str(bad)], ["grade", str(bad), str(CLASS / "ada")]):
        result = CliRunner().invoke(main, command)
        assert result.exit_code == 2, result.output
        assert f"{bad}:{line}:" in result.output and "'WallFolow' is no node type" in result.output
        assert "did you mean 'WallFollow'?" in result.output and "Traceback" not in result.output


def test_a_penalty_is_its_own_csv_column_and_junit_testcase_with_each_finding():
    graded = grade(PART12, [CLASS / "chen"], workers=2)  # uses WallFollow, forbidden at 4 points
    results = graded.to_json()
    (student,) = results["students"]
    assert student["penalty"] == -4 and student["score"] == sum(c["earned"] for c in student["criteria"]) - 4
    (row,) = csv.DictReader(io.StringIO(gradebook_csv(graded)))
    names = [c["name"] for c in results["assignment"]["criteria"]]
    assert float(row["penalty"]) == -4
    assert sum(float(row[n]) for n in names) + float(row["penalty"]) == float(row["score"])
    assert (
        "WallFollow is not allowed in this assignment (at " in row["palette"] and "chen/part1_2.yaml:" in row["palette"]
    )
    assert float(row["part 2 turns left at each wall @ course"]) == 0
    suite = ET.fromstring(junit_xml(graded)).find("testsuite")
    assert suite is not None
    palette = next(c for c in suite.findall("testcase") if c.get("name") == "palette")
    failure = palette.find("failure")
    assert failure is not None and failure.get("message") == "1 palette rule(s) broken, -4 points"
    assert "WallFollow is not allowed" in (failure.text or "")
    assert int(suite.get("failures") or 0) == sum(c.find("failure") is not None for c in suite.findall("testcase"))


@pytest.mark.parametrize(("written", "mib"), [("512MiB", 512), ("2GiB", 2048), ("512MB", 488), ("768", 768)])
def test_a_memory_limit_takes_units(tmp_path, written, mib):
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: a\nvariants: [{name: v, maze: two_parts_maze}]\ncriteria: [{name: c, points: 1, finishes: true}]\n"
        f"limits: {{memory: {written}}}\n"
    )
    assert round(load_assignment(assignment).limits.memory) == mib


def test_a_memory_limit_in_another_unit_says_which_are_taken(tmp_path):
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: a\nvariants: [{name: v, maze: two_parts_maze}]\ncriteria: [{name: c, points: 1, finishes: true}]\n"
        "limits: {memory: 5cm}\n"
    )
    with pytest.raises(
        UserError, match="a.yaml:4:18: expected a memory .in MiB., got a length .*hint: write a memory: 512MiB or 2GiB"
    ):
        load_assignment(assignment)


def _corridor_run(events: list[dict], trajectory: list[tuple[float, float, float, float]]) -> RunFacts:
    maze = path_maze([(0, 0), (1, 0), (2, 0)])  # a corridor closed at x = 0.6
    run = SimpleNamespace(
        status=RunStatus.SUCCESS,
        reason=None,
        failed_path=None,
        sim_time=trajectory[-1][0],
        final_pose=Pose(*trajectory[-1][1:]),
        collisions=0,
        min_clearance=0.01,
        events=events,
        trajectory=trajectory,
        goal=None,
    )
    return RunFacts(run, maze, robot_model("course"), time_limit=60.0)


def test_a_stop_is_blamed_on_the_move_that_set_the_distance_not_the_turn_after_it(tmp_path):
    """Issue 46: a dead-end stop at 1.4 cm was blamed on the TurnAngle after it (the last node to
    end), not on the MoveUntilWall that drove the robot there."""
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: a\nvariants: [{name: course, maze: two_parts_maze, start: part1, noise: off}]\n"
        "criteria: [{name: stop, points: 1, gap: {at: end, distance: 5cm, tolerance: 5mm}}]\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: two_parts_maze\nstart: part1\ntree:\n  sequence:\n    children:\n"
        "      - MoveUntilWall: {name: centre the axle, distance: 1.5cm}\n"
        "      - TurnAngle: {angle: 360deg}\n"  # on the spot: base_link swings, the axle stays
    )
    (student,) = grade(assignment, [mission], workers=1).to_json()["students"]
    (criterion,) = student["criteria"]
    assert criterion["feedback"].startswith("stopped 1.5 cm from the wall, wanted 5.0 +- 0.5 cm")
    assert criterion["where"] == f"{mission}:6"  # the MoveUntilWall, not the TurnAngle on line 7


def test_a_dead_end_counts_only_after_the_node_it_names(tmp_path):
    drive = [(0.1 * i, 0.1 + 0.0389 * i, 0.1, 0.0) for i in range(11)]  # stops 5 cm from the end wall
    events = [{"t": 1.0, "kind": "behaviour_end", "name": "MoveUntilWall", "path": "m/part 1"}]
    facts = _corridor_run(events, drive)
    after_part_2 = Criterion(name="d", points=1, dead_end={"distance": "5cm", "after": "m/part 2*"})
    judged = judge(after_part_2, facts)
    assert not judged.passed and judged.feedback == "the run ended before any m/part 2* ended, so not at the dead end"
    assert judge(Criterion(name="d", points=1, dead_end={"distance": "5cm", "after": "m/part 1"}), facts).passed


def test_every_problem_of_an_assignment_is_reported_in_one_round(tmp_path):
    """Issue 46: the schema's, the variants', the maze's and the start's problems came in four
    rounds of validate."""
    bad = tmp_path / "a.yaml"
    bad.write_text(
        "name: a\nvariants:\n"
        "  - {name: a, maze: two_parts_maze, start: part9}\n"
        "  - {name: b, maze: no_such_maze}\n"
        "  - {name: b, maze: two_parts_maze}\n"
        "criteria:\n"
        "  - {name: x, points: 1, finishes: true, variants: [c]}\n"
        "  - {name: y, points: -1, finishes: true}\n"
    )
    result = CliRunner().invoke(main, ["validate", str(bad)])
    assert result.exit_code == 2
    lines = [line for line in result.output.splitlines() if line.startswith("error: ")]
    for expected in (
        f"{bad}:8:23: Input should be greater than 0",  # the schema
        f"{bad}:5:12: variant 'b' is defined twice",
        f"{bad}:7:53: criterion 'x' names no variant 'c'",
        f"{bad}:3:44: variant 'a': its maze has no spawn 'part9'",
        f"{bad}:4:21: maze not found: 'no_such_maze'",
    ):
        assert any(line.startswith(f"error: {expected}") for line in lines), (expected, lines)


HIDDEN = """\
name: hidden_worlds
submission: part1_2.yaml
variants:
  - {name: course, maze: two_parts_maze, start: part1, seeds: 1, noise: off}
  - {name: secret_box, maze: ASSIGNMENTS/worlds/part12_long_part1.yaml, start: [0.18, 0.1, 0], visibility: hidden,
     noise: off}
  - {name: secret_corridor, generate: {kind: path, length: 6, seed: secret, turns: left}, visibility: hidden,
     noise: off}
criteria:
  - {name: part 1 stops 5 cm from the wall, points: 2, gap: {at: delete, distance: 5cm, tolerance: 5mm},
     variants: [course, secret_box]}
  - {name: never touches a wall, points: 1, no_collision: true}
"""


def _hidden_assignment(tmp_path: Path) -> Path:
    path = tmp_path / "hidden.yaml"
    path.write_text(HIDDEN.replace("ASSIGNMENTS", str(PART12.parent)))
    return path


def test_a_secret_seed_needs_the_course_s_secret_and_draws_another_world_for_another_secret(tmp_path, monkeypatch):
    from thymio_bt.grade.worlds import course_secret, load_worlds

    assignment = _hidden_assignment(tmp_path)
    monkeypatch.delenv("THYMIO_BT_SECRET", raising=False)
    result = CliRunner().invoke(main, ["validate", str(assignment)])
    assert result.exit_code == 2 and "its maze's seed is secret, and no secret was given" in result.output
    assert f"{assignment}:7:" in result.output and "THYMIO_BT_SECRET" in result.output
    walls = {}
    for secret in ("one secret", "another secret"):
        _, worlds = load_worlds(assignment, tmp_path / secret, secret)
        corridor = next(w for w in worlds if w.name == "secret_corridor")
        assert corridor.maze is not None and corridor.maze.name == "secret_corridor"  # no seed in its name
        walls[secret] = corridor.maze.walls
    assert walls["one secret"] != walls["another secret"]
    secret_file = tmp_path / "secret.txt"
    secret_file.write_text("one secret\n")
    monkeypatch.setenv("THYMIO_BT_SECRET", "one secret")
    by_env = load_worlds(assignment, tmp_path / "env", course_secret())[1][2].maze
    by_file = load_worlds(assignment, tmp_path / "file", course_secret(secret_file))[1][2].maze
    assert by_env is not None and by_file is not None and by_env.walls == by_file.walls == walls["one secret"]


def test_student_pages_carry_nothing_of_a_hidden_world(tmp_path, monkeypatch):
    monkeypatch.setenv("THYMIO_BT_SECRET", "course secret")
    assignment = _hidden_assignment(tmp_path)
    (sub := tmp_path / "subs" / "dana").mkdir(parents=True)
    (sub / "part1_2.yaml").write_text((CLASS / "dana" / "part1_2.yaml").read_text())
    site, out = tmp_path / "site", tmp_path / "results.json"
    args = ["grade", str(assignment), str(sub), "--html", str(site), "--for-students", "--out", str(out)]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert f"wrote the site: {site / 'index.html'} (3 pages)" in result.output
    text = "\n".join(p.read_text() for p in site.rglob("*") if p.is_file() and p.parent.name != "replays")
    names = ["dana.html", "dana_course_seed0.html", "index.html", "replays", "students"]
    assert sorted(p.name for p in site.rglob("*")) == names  # no worlds/, no hidden world's replay
    assert "secret_box" not in (site / "replays" / "dana_course_seed0.html").read_text()
    assert sorted(p.name for p in (tmp_path / "results_worlds").iterdir()) == [
        "secret_box.yaml",
        "secret_corridor.yaml",
    ]
    for secret in ("secret_box", "secret_corridor", "part12_long_part1", "0.18"):
        assert secret not in text, secret
    assert text.count("thymio-bt run ") == 1  # the one run of the public world, which failed
    assert text.count("thymio-bt check ") == 1 and "--variant course --seed 0" in text
    assert "<code>None</code>" not in text
    assert "<li>hidden world 1: 0 points: stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm</li>" in text
    assert "variant course, seed 0" in text and 'data-variant="course"' in text  # the public world is drawn
    # the TA's results keep everything
    import json

    ta = json.loads(out.read_text())
    assert {v["name"]: v["visibility"] for v in ta["assignment"]["variants"]}["secret_box"] == "hidden"
    assert any(r["variant"] == "secret_box" and r["reproduce"] for r in ta["students"][0]["runs"])


def test_check_judges_the_public_variants_with_the_grader_s_words(tmp_path, monkeypatch):
    monkeypatch.setenv("THYMIO_BT_SECRET", "course secret")
    assignment = _hidden_assignment(tmp_path)
    good = CliRunner().invoke(main, ["check", str(assignment), str(CLASS / "ada" / "part1_2.yaml")])
    assert good.exit_code == 0, good.output
    assert good.output.startswith("hidden_worlds: 1 public variant (course), 1 run\n")
    late = CliRunner().invoke(main, ["check", str(assignment), str(CLASS / "dana" / "part1_2.yaml")])
    assert late.exit_code == 1
    assert "FAIL  part 1 stops 5 cm from the wall  0 / 2\n      stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm" in (
        late.output
    )
    assert "secret" not in late.output


def test_a_run_s_check_command_prints_the_grader_s_judgement_of_it(tmp_path, monkeypatch):
    """Issue 42: a reproduce command printed SUCCESS for a run the grader failed."""
    import json
    import shlex

    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "dana").mkdir()
    (subs / "dana" / "part1_2.yaml").write_text((CLASS / "dana" / "part1_2.yaml").read_text())
    out = tmp_path / "out" / "results.json"
    out.parent.mkdir()
    result = CliRunner().invoke(main, ["grade", str(PART12), str(subs / "dana"), "--out", str(out)])
    assert result.exit_code == 0, result.output
    runs = json.loads(out.read_text())["students"][0]["runs"]
    run = next(r for r in runs if r["variant"] == "tall_part2" and r["seed"] == 2)
    for command in (run["reproduce"], run["check"]):  # relative to the results, shipped files by name
        assert str(ROOT) not in command and str(tmp_path) not in command
    assert " --maze results_worlds/tall_part2.yaml " in run["reproduce"]  # a copy beside the results
    assert run["check"] == "thymio-bt check course_part1_2 ../subs/dana/part1_2.yaml --variant tall_part2 --seed 2"
    course = next(r for r in runs if r["variant"] == "course")
    assert " --maze two_parts_maze " in course["reproduce"]
    monkeypatch.chdir(out.parent)
    args = shlex.split(run["check"])[1:]
    checked = CliRunner().invoke(main, args)
    assert checked.exit_code == 1
    for name, judged in run["criteria"].items():
        line = f"{'pass' if judged['passed'] else 'FAIL'}  {name}  "
        assert line in checked.output, (line, checked.output)
        if not judged["passed"]:
            assert f"      {judged['feedback']} (variant tall_part2, seed 2, robot real; failed 1 of 1 runs)" in (
                checked.output
            )


@pytest.mark.parametrize(
    ("children", "passed"),
    [
        # stops 9 cm from the wall, waits, then creeps on to 5 cm: its part 1 stop is the first one
        (
            ["MoveUntilWall: {speed: 10cm/s, distance: 9cm}", "Wait: {seconds: 1}", "MoveUntilWall: {distance: 5cm}"],
            False,
        ),
        # stops at 5 cm, then turns and drives on elsewhere: the stop before any delete still counts
        (
            [
                "MoveUntilWall: {speed: 10cm/s, distance: 5cm}",
                "TurnAngle: {angle: 90deg}",
                "MoveUntilWall: {distance: 5cm}",
            ],
            True,
        ),
    ],
)
def test_a_run_that_never_deletes_the_robot_is_judged_where_it_first_stopped(tmp_path, children, passed):
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: a\nvariants: [{name: course, maze: two_parts_maze, start: part1, noise: off}]\n"
        "criteria: [{name: part 1, points: 1, gap: {at: delete, distance: 5cm, tolerance: 5mm}}]\n"
    )
    mission = tmp_path / "m.yaml"
    body = "".join(f"      - {child}\n" for child in children)
    mission.write_text(f"maze: two_parts_maze\nstart: part1\ntree:\n  sequence:\n    children:\n{body}")
    (student,) = grade(assignment, [mission], workers=1).to_json()["students"]
    (criterion,) = student["criteria"]
    assert criterion["passed"] is passed, criterion["feedback"]
    if not passed:
        assert criterion["feedback"].startswith("stopped 8.9 cm from the wall")
        assert criterion["where"] == f"{mission}:6"
