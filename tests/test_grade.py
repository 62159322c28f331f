"""thymio-bt grade: a class of submissions with known defects, each losing the right points; correct
ones, however written, getting full marks; invalid files; submissions that hang, crash, exit or
exhaust memory failing their own runs while the grade goes on."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from _waiting import wait_until
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.grade.assignment import load_assignment
from thymio_bt.grade.grader import grade
from thymio_bt.maze.files import load_maze
from thymio_bt.robot.interface import Pose

ROOT = Path(__file__).resolve().parent.parent
PART12 = ROOT / "assignments" / "course_part1_2.yaml"
CLASS = ROOT / "examples" / "class"

CORRECT_LOOP = (CLASS / "ada" / "part1_2.yaml").read_text()

#: a correct submission written another way: the turn decided by ChooseTurn through the blackboard,
#: part 2 as a retry of legs, a selector to end at the dead end
CORRECT_OTHER = """
name: other
maze: two_parts_maze
start: part1
parameters: {gap: 5cm}
tree:
  sequence:
    name: all
    children:
      - MoveUntilWall: {name: first wall, speed: 10cm/s, distance: $gap}
      - DeleteEntity: {entity: thymio}
      - SpawnEntity: {entity: thymio, pose: part2}
      - repeat:
          name: legs
          until: IsDeadEnd
          do:
            sequence:
              name: leg
              children:
                - parallel:
                    name: go
                    policy: success_on_all
                    children:
                      - MoveUntilWall: {speed: 12cm/s, distance: $gap, centre: true}
                      - ChooseTurn: {}
                - selector:
                    name: done or turn
                    children:
                      - IsDeadEnd
                      - sequence:
                          name: turn
                          children:
                            - MoveUntilWall: {speed: 12cm/s, distance: 1.5cm}
                            - TurnAngle: {angle: bb:turn_angle}
"""


def _class(tmp_path: Path, files: dict[str, str]) -> list[Path]:
    folders = []
    for name, text in files.items():
        folder = tmp_path / "subs" / name
        folder.mkdir(parents=True)
        (folder / "part1_2.yaml").write_text(text)
        folders.append(folder)
    return folders


def _by_name(results: dict) -> dict[str, dict]:
    return {s["name"]: s for s in results["students"]}


def _missed(student: dict) -> set[str]:
    return {c["name"] for c in student["criteria"] if not c["passed"]}


@pytest.fixture(scope="module")
def graded(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The part 1-2 assignment graded on a class with known defects."""
    tmp = tmp_path_factory.mktemp("class")
    folders = _class(
        tmp,
        {
            "correct_loop": CORRECT_LOOP,
            "correct_other": CORRECT_OTHER,
            "stops_7cm": CORRECT_LOOP.replace("speed: 10cm/s, distance: 5cm}", "speed: 10cm/s, distance: 7cm}"),
            "wrong_respawn": CORRECT_LOOP.replace("pose: [0.5, 0.3, pi/2]", "pose: [0.5, 0.32, pi/2]"),
            "wallfollow": (CLASS / "chen" / "part1_2.yaml").read_text(),
            "blind": (CLASS / "bob" / "part1_2.yaml").read_text(),
            "broken": "name: x\nmaze: two_parts_maze\nstart: part1\ntree:\n  Sequense: []\n",
        },
    )
    (tmp / "subs" / "empty").mkdir()
    return grade(PART12, [*folders, tmp / "subs" / "empty"], workers=2, worlds=tmp / "worlds").to_json()


def test_correct_submissions_get_full_marks_however_written(graded):
    students = _by_name(graded)
    for name in ("correct_loop", "correct_other"):
        assert students[name]["status"] == "graded"
        assert students[name]["score"] == students[name]["max"] == 11, _missed(students[name])
        assert all(c["runs"] == 12 for c in students[name]["criteria"])


def test_each_defect_loses_its_points_with_feedback_and_place(graded):
    students = _by_name(graded)
    late = students["stops_7cm"]
    assert _missed(late) == {"part 1 stops 5 cm from the wall"}  # part 2 still stops at 5 cm
    assert late["score"] == 9
    first = next(c for c in late["criteria"] if c["name"] == "part 1 stops 5 cm from the wall")
    assert first["feedback"].startswith("stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm (variant course")
    assert first["where"].endswith("stops_7cm/part1_2.yaml:11")  # the MoveUntilWall of part 1

    respawn = students["wrong_respawn"]
    assert "respawns at (0.5, 0.3, yaw pi/2)" in _missed(respawn)
    spawn = next(c for c in respawn["criteria"] if c["name"] == "respawns at (0.5, 0.3, yaw pi/2)")
    assert "spawned at (0.500, 0.320" in spawn["feedback"] and spawn["where"].endswith("part1_2.yaml:13")


def test_a_forbidden_node_costs_the_penalty_and_is_named(graded):
    student = _by_name(graded)["wallfollow"]
    (finding,) = student["palette"]
    assert finding["node"] == "WallFollow" and finding["points"] == 4
    assert finding["where"].endswith("wallfollow/part1_2.yaml:13")
    earned = sum(c["earned"] for c in student["criteria"])
    assert student["score"] == max(0, earned - 4)


def test_a_blind_odometry_solution_loses_the_worlds_it_was_not_written_for(graded):
    blind = _by_name(graded)["blind"]
    assert blind["score"] <= blind["max"] / 2  # the course's share of each criterion, and little else
    for criterion in blind["criteria"]:
        shares = {v["name"]: v["earned"] for v in criterion["variants"]}
        assert shares["course"] == criterion["points"] / 4, criterion["name"]
        if criterion["name"] in ("part 1 stops 5 cm from the wall", "part 2 turns left at each wall"):
            assert shares["long_part1"] == shares["shifted_start"] == 0
    per_variant: dict[str, set[bool]] = {}
    for run in blind["runs"]:
        per_variant.setdefault(run["variant"], set()).add(run["criteria"]["never touches a wall"]["passed"])
    assert per_variant["course"] == {True}  # it works where it was measured...
    assert per_variant["long_part1"] == per_variant["shifted_start"] == {False}  # ...and nowhere else


def test_broken_and_empty_submissions_are_graded_invalid_with_their_messages(graded):
    students = _by_name(graded)
    broken, empty = students["broken"], students["empty"]
    assert broken["status"] == empty["status"] == "invalid"
    assert broken["score"] == 0 and "broken/part1_2.yaml:5:3" in broken["messages"][0]
    assert "did you mean 'sequence'" in broken["messages"][0]
    assert empty["messages"] == ["no part1_2.yaml, nor any mission file (.yaml or .xml) in empty"]


def test_each_failed_run_carries_the_command_that_reproduces_it(graded):
    late = _by_name(graded)["stops_7cm"]
    run = next(r for r in late["runs"] if r["variant"] == "tall_part2")
    assert run["reproduce"].startswith("thymio-bt run ") and "--seed" in run["reproduce"]
    assert "--set robot=real" in run["reproduce"] and "worlds/tall_part2.yaml" in run["reproduce"]
    assert sum("trajectory" in r for r in late["runs"]) == 4  # one picture per variant


def test_coverage_names_every_node_and_those_never_ticked(graded):
    coverage = _by_name(graded)["correct_loop"]["coverage"]
    assert coverage["runs"] == 12
    ticked = {n["path"]: n["ticks"] for n in coverage["nodes"]}
    assert ticked["mission/part 1"] > 0 and not coverage["never_ticked"]


def _plugin_class(tmp_path: Path, bodies: dict[str, str], wall: str = "3s") -> tuple[Path, list[Path]]:
    """An assignment that allows plugins (one short world, runs limited to 1 s of CPU and ``wall`` of
    wall-clock time), and a submission per plugin body."""
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: plugins\nvariants:\n  - {name: course, maze: two_parts_maze, start: part1, seeds: 2, noise: off}\n"
        "criteria:\n  - {name: ends well, points: 1, finishes: true}\n"
        f"palette: {{plugins: true}}\nlimits: {{cpu: 1s, wall: {wall}, memory: 1024}}\n"
    )
    folders = []
    for name, body in bodies.items():
        folder = tmp_path / name
        folder.mkdir()
        (folder / "nodes.py").write_text(
            "import os, sys\nfrom py_trees.common import Status\nfrom thymio_bt.behaviours import RobotBehaviour\n"
            "class Bad(RobotBehaviour):\n    '''A node that misbehaves.'''\n"
            f"    def step(self):\n        {body}\n        return Status.SUCCESS\n"
        )
        (folder / "m.yaml").write_text(
            "maze: two_parts_maze\nstart: part1\nplugins: [nodes.py]\ntree:\n  sequence:\n    children:\n"
            "      - MoveUntilWall: {speed: 10cm/s, distance: 5cm}\n      - Bad\n"
        )
        folders.append(folder)
    good = tmp_path / "good"
    good.mkdir()
    (good / "m.yaml").write_text("maze: two_parts_maze\nstart: part1\ntree:\n  MoveUntilWall: {distance: 5cm}\n")
    return assignment, [*folders, good]


def test_hanging_crashing_exiting_and_greedy_submissions_fail_their_own_runs(tmp_path):
    assignment, folders = _plugin_class(
        tmp_path,
        {
            "sleeps": "import time; time.sleep(3600)",
            "crashes": "os._exit(3)",
            "exits": "sys.exit(0)",
            "greedy": "x = bytearray(4 << 30)",
            "spawns": "import subprocess; subprocess.Popen(['sleep', '1000'], start_new_session=False)",
        },
    )
    results = _by_name(grade(assignment, folders, workers=2).to_json())
    reasons = {name: results[name]["runs"][0]["reason"] for name in ("sleeps", "crashes", "exits", "greedy")}
    assert reasons["sleeps"] == "the run went over its wall-clock time limit of 3 s, in 'sequence/Bad'"
    assert reasons["crashes"] == (
        "the submission's process ended during the run (os._exit, a crash, or its memory limit of 1024 MiB)"
    )
    assert "sys.exit" in reasons["exits"] or results["exits"]["runs"][0]["code"] == "EXCEPTION"
    assert "memory" in reasons["greedy"] or "MemoryError" in reasons["greedy"]
    for name in reasons:
        assert results[name]["status"] == "graded" and len(results[name]["runs"]) == 2
        assert results[name]["score"] == 0
    assert results["good"]["score"] == 1  # the grade went on for everyone else
    # a confined submission may not run a program (Landlock: /usr/bin is out of its reach)
    assert "PermissionError" in results["spawns"]["runs"][0]["reason"]
    assert not [p for p in Path("/proc").glob("[0-9]*/cmdline") if _read(p) == b"sleep\x001000\x00"]


def test_a_submission_that_hangs_uses_up_its_cpu_time_limit(tmp_path):
    """The CPU limit, whatever the load: the wall-clock limit (600 s) is only against a hang. With the
    3 s of the test above, a loaded machine gave the loop less than 1 s of CPU in 3 s."""
    assignment, folders = _plugin_class(tmp_path, {"hangs": "while True: pass"}, wall="600s")
    results = _by_name(grade(assignment, folders, workers=2).to_json())
    hangs = results["hangs"]
    assert [run["reason"] for run in hangs["runs"]] == [
        "the run used more than its CPU time limit of 1 s, in 'sequence/Bad'"
    ] * 2
    assert hangs["status"] == "graded" and hangs["score"] == 0 and results["good"]["score"] == 1


def test_plugins_are_refused_where_the_assignment_forbids_them(tmp_path):
    _, folders = _plugin_class(tmp_path, {"sneaky": "pass"})
    results = _by_name(grade(PART12, folders[:1], workers=1).to_json())
    student = results["sneaky"]
    assert student["status"] == "invalid" and student["runs"] == []
    assert "plugins are not allowed in this assignment (nodes.py)" in student["messages"][0]


def test_a_module_plugin_is_refused_where_the_assignment_forbids_plugins(tmp_path):
    """Before: only .py files counted as plugins, so `plugins: [nodes:Bad]` (a module the grader's
    path may find, e.g. the folder `python -m` was started in) passed a no-plugin palette."""
    _, folders = _plugin_class(tmp_path, {"modular": "pass"})
    mission = folders[0] / "m.yaml"
    mission.write_text(mission.read_text().replace("plugins: [nodes.py]", "plugins:\n  - nodes:Bad"))
    student = _by_name(grade(PART12, folders[:1], workers=1).to_json())["modular"]
    assert student["status"] == "invalid" and student["runs"] == []
    assert student["messages"][0].startswith(f"{mission}:4")
    assert "plugins are not allowed in this assignment (nodes:Bad)" in student["messages"][0]


def test_the_command_writes_json_csv_and_valid_junit(tmp_path):
    subs = tmp_path / "subs"
    shutil.copytree(CLASS, subs)
    out, csv, junit = tmp_path / "r.json", tmp_path / "g.csv", tmp_path / "j.xml"
    result = CliRunner().invoke(
        main,
        [
            "grade",
            str(PART12),
            *map(str, sorted(subs.iterdir())),
            "--out",
            str(out),
            "--csv",
            str(csv),
            "--junit",
            str(junit),
            "--fail-under",
            "5",
        ],
    )
    assert result.exit_code == 1, result.output  # bob, chen and eve scored under 5
    results = json.loads(out.read_text())
    assert [s["name"] for s in results["students"]] == ["ada", "bob", "chen", "dana", "eve"]
    assert csv.read_text().splitlines()[1].startswith("ada,graded,11,11,2,1,1,1,2,2,1,1,0,,0.5,0.5,")
    root = ET.parse(junit).getroot()
    assert root.tag == "testsuites" and len(root.findall("testsuite")) == 5
    for suite in root.findall("testsuite"):
        cases = suite.findall("testcase")
        assert int(suite.get("tests")) == len(cases) == 9  # 8 criteria and the palette
        assert int(suite.get("failures")) == sum(c.find("failure") is not None for c in cases)
        assert int(suite.get("errors")) == sum(c.find("error") is not None for c in cases)
    # as autograders read it (junitparser, an independent reader of JUnit XML)
    from junitparser import Error, Failure, JUnitXml

    for suite, student in zip(JUnitXml.fromfile(str(junit)), results["students"], strict=True):
        assert (suite.name, suite.tests) == (student["name"], 9)
        for case, criterion in zip(list(suite)[:-1], student["criteria"], strict=True):
            outcome = [type(r) for r in case.result]
            if student["status"] != "graded":
                assert outcome == [Error]
            elif criterion["passed"]:
                assert outcome == []
            else:
                assert outcome == [Failure] and case.result[0].message == criterion["feedback"]
    assert "most missed" in result.output


def test_bad_assignments_are_user_errors_with_places(tmp_path):
    bad = tmp_path / "a.yaml"
    bad.write_text(
        "name: a\nvariants:\n  - {name: v, maze: two_parts_maze}\ncriteria:\n"
        "  - {name: c, points: 1, no_collision: true, variants: [w]}\n  - {name: d, points: 1}\n"
    )
    with pytest.raises(UserError) as err:
        load_assignment(bad)
    messages = [str(p) for p in err.value.problems]
    assert any(m.startswith(f"{bad}:6:5: a criterion makes exactly one check, this one makes 0") for m in messages)
    result = CliRunner().invoke(main, ["grade", str(bad), str(CLASS / "ada")])
    assert result.exit_code == 2 and "Traceback" not in result.output


def test_the_committed_assignment_schema_is_the_generated_one_and_accepts_the_shipped_assignments():
    import jsonschema
    import yaml

    from thymio_bt.grade.assignment import assignment_schema

    committed = json.loads((ROOT / "schema" / "assignment.schema.json").read_text())
    assert committed == assignment_schema(), "run: thymio-bt schema --assignment -o schema/assignment.schema.json"
    shipped = sorted((ROOT / "assignments").glob("*.yaml"))
    assert [p.stem for p in shipped] == ["course_6x6", "course_bonus", "course_part1_2", "micromouse"]
    for path in shipped:
        jsonschema.validate(yaml.safe_load(path.read_text()), committed)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"name": "a", "variants": [{"name": "v", "mazee": "x"}], "criteria": []}, committed)


def test_validate_checks_assignments_and_their_worlds(tmp_path):
    result = CliRunner().invoke(main, ["validate", *map(str, sorted((ROOT / "assignments").glob("*.yaml")))])
    assert result.exit_code == 0, result.output
    assert "ok: " in result.output and "course_part1_2.yaml (assignment: 4 variants (12 runs a submission)" in (
        result.output
    )
    bad = tmp_path / "a.yaml"
    bad.write_text(
        "name: a\nvariants:\n  - {name: v, maze: two_parts_maze, start: part3}\n"
        "criteria:\n  - {name: c, points: 1, no_collision: true}\n"
    )
    result = CliRunner().invoke(main, ["validate", str(bad)])
    assert result.exit_code == 2
    assert f"{bad}:3:44: variant 'v': its maze has no spawn 'part3'" in result.output
    assert "did you mean 'part2'?" in result.output


def test_a_shipped_assignment_is_found_by_name():
    from thymio_bt.grade.assignment import load_assignment

    assert load_assignment("course_bonus").name == "course_bonus"
    with pytest.raises(UserError, match="did you mean 'course_6x6'"):
        load_assignment("course_6x7")


@pytest.mark.parametrize(
    ("assignment", "solution", "penalty"),
    [
        ("course_bonus", "missions/maze_bonus.yaml", 3),  # it includes the library, which the bonus forbids
        ("course_6x6", "examples/wall_follower_left.yaml", 0),
        ("course_6x6", "examples/wall_follower_right.yaml", 0),
        ("micromouse", "missions/micromouse.yaml", 0),
    ],
)
def test_the_shipped_solutions_pass_every_criterion_of_the_shipped_assignments(assignment, solution, penalty):
    (student,) = grade(assignment, [ROOT / solution], workers=2).to_json()["students"]
    assert student["status"] == "graded"
    assert not _missed(student), [c["feedback"] for c in student["criteria"] if not c["passed"]]
    assert student["score"] == student["max"] - penalty
    if penalty:  # named where the student's file includes the library, as every other finding is
        line = next(n for n, text in enumerate((ROOT / solution).read_text().splitlines(), 1) if "include:" in text)
        assert [f["where"] for f in student["palette"]] == [f"{ROOT / solution}:{line}"]


def test_ctrl_c_stops_the_grade_at_once_keeps_what_was_done_and_leaves_no_child(tmp_path):
    """Ctrl-C as soon as the grader says (its line per student, on a pipe) that a first student is graded."""
    import signal
    import subprocess
    import sys

    folders = _class(tmp_path, {f"s{i:02d}": CORRECT_LOOP for i in range(30)})
    out = tmp_path / "r.json"
    cmd = [sys.executable, "-m", "thymio_bt.cli", "grade", str(PART12), *map(str, folders), "--out", str(out)]
    process = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stderr is not None
    said = [process.stderr.readline()]
    while not said[-1].startswith("graded 1/30: "):
        assert said[-1], "".join(said)  # it ended first
        said.append(process.stderr.readline())
    # grading the others (between two students a worker may be forking the next one's process)
    wait_until(lambda: bool(_children(process.pid)) or process.poll() is not None, "a worker grading")
    children = _children(process.pid)
    assert children, "".join(said)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)  # only against a hang
    assert process.returncode == 130, err
    assert not [pid for pid in children if _alive(pid)] and "Traceback" not in err
    results = json.loads(out.read_text())
    statuses = {s["status"] for s in results["students"]}
    assert "interrupted" in statuses  # those not finished say so...
    assert len(results["students"]) == 30  # every student is in the results
    interrupted = [s for s in results["students"] if s["status"] == "interrupted"]
    assert all(s["messages"][-1].startswith("interrupted after ") for s in interrupted)
    # ...the others stand: a correct mission's full marks (the assignment's, 11 since the speed criterion)
    graded = [s for s in results["students"] if s["status"] == "graded"]
    assert graded and all(s["score"] == s["max"] == 11 for s in graded)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` still runs (a zombie does not)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0] != "Z"
    except OSError:
        return False


def _read(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError:
        return b""


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rpartition(")")[2].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def test_the_progress_line_says_students_runs_rate_and_time_left(monkeypatch, capsys):
    from thymio_bt.cli.grading import _Progress
    from thymio_bt.grade.results import RunMessage

    progress = _Progress()
    progress.enabled = True
    progress.start({"ada": 2, "bob": 2})
    run = RunMessage(index=0, variant="course", seed=0, robot="course", status="SUCCESS", criteria={})
    for student in ("ada", "ada", "bob", "bob"):
        progress(student, run)
    line = capsys.readouterr().err.split("\r")[-1]
    assert line.startswith("graded 2/2 students, 4/4 runs, ") and " runs/s, 0 s left" in line


def test_a_gap_after_a_node_is_measured_when_that_node_ended(tmp_path):
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: a\nvariants:\n  - {name: c, maze: two_parts_maze, start: part1, noise: off}\ncriteria:\n"
        "  - {name: first stop, points: 1, gap: {after: MoveUntilWall, distance: 5cm}}\n"
        "  - {name: part 1, points: 1, gap: {after: mission/part 1, distance: 5cm}}\n"
    )
    students = _by_name(grade(assignment, [CLASS / "ada", CLASS / "dana"], workers=1).to_json())
    assert students["ada"]["score"] == 2 and students["dana"]["score"] == 0
    assert students["dana"]["criteria"][1]["where"].endswith("dana/part1_2.yaml:10")
    bad = tmp_path / "b.yaml"
    bad.write_text(assignment.read_text().replace("{after: MoveUntilWall, ", "{at: end, after: MoveUntilWall, "))
    with pytest.raises(UserError, match="give the moment to measure"):
        load_assignment(bad)


def test_coverage_says_which_child_ended_each_composite(graded):
    nodes = {n["path"]: n for n in _by_name(graded)["correct_loop"]["coverage"]["nodes"]}
    ended = nodes["mission/part 2/one corridor/end or turn"]["ended_by"]
    assert ended["mission/part 2/one corridor/end or turn/IsDeadEnd"] == 12  # once a run, at the dead end
    assert ended["mission/part 2/one corridor/end or turn/turn left"] > 12


def test_generated_corridors_of_another_pitch_grade_the_route_not_the_looks(tmp_path):
    """`cell` makes a corridor on a 0.25 m grid, wider than the course robot's side rays reach: the
    shipped bonus mission stops to look (a quarter turn and back, or three) and still takes the
    corridor's turns; the `turns` criterion counts the route's turns, not the looks."""
    from thymio_bt.grade.assignment import Variant
    from thymio_bt.grade.worlds import World

    variant = {"name": "wide", "generate": {"kind": "path", "length": 10, "seed": 2, "cell": "25cm"}, "noise": "off"}
    world = World.of(Variant(**variant), tmp_path, tmp_path)
    ends = {round(c, 3) for wall in load_maze(world.maze_file).walls for point in (wall.start, wall.end) for c in point}
    assert ends <= {round(0.25 * i, 3) for i in range(12)}
    assignment = tmp_path / "wide.yaml"
    assignment.write_text(
        "name: wide\nsubmission: bonus.yaml\ntime_limit: 300s\nvariants:\n"
        f"  - {json.dumps(variant)}\n"
        "criteria:\n  - {name: turns, points: 1, turns: true}\n"
        "  - {name: dead end, points: 1, dead_end: {distance: 5cm, tolerance: 5mm}}\n"
    )
    (student,) = grade(assignment, [ROOT / "missions" / "maze_bonus.yaml"]).to_json()["students"]
    assert student["score"] == 2, [c["feedback"] for c in student["criteria"]]


@pytest.mark.parametrize("cell", [0.2, 0.4])
def test_a_dead_end_is_judged_on_the_maze_s_own_grid(cell):
    """At the far end of a corridor, centred, 5 cm from the wall: a dead end on any grid (a fixed
    0.15 m once said the side walls of a 0.4 m cell, 0.195 m away, were openings); one cell
    earlier, where the corridor turns, a side is open."""
    from types import SimpleNamespace

    from thymio_bt.grade.assignment import Criterion
    from thymio_bt.grade.checks import RunFacts, judge
    from thymio_bt.maze.generate import path_maze
    from thymio_bt.robot.model import COURSE

    maze = path_maze([(0, 0), (1, 0), (1, 1), (2, 1)], cell=cell)  # right, up, right: ends at x = 3 cells
    stop = 3 * cell - 0.005 - 0.05 - (COURSE.sensors[2].x)  # front sensor 5 cm from the end wall's face

    def judged(x: float, y: float) -> tuple[bool, str | None]:
        run = SimpleNamespace(events=[], trajectory=[(0.0, x, y, 0.0)], final_pose=Pose(x, y, 0.0))
        facts = RunFacts(run, maze, COURSE, time_limit=60.0, cell=cell)
        verdict = judge(Criterion(name="end", points=1, dead_end={"distance": "5cm", "tolerance": "5mm"}), facts)
        return verdict.passed, verdict.feedback

    assert judged(stop, 1.5 * cell) == (True, None)
    assert judged(stop - cell, 0.5 * cell) == (False, "stopped where the left side is open: not a dead end")


def test_a_confined_run_knows_its_maze_s_goal_region(tmp_path):
    """A submission with plugins ticks its tree in a sandbox, which gets the maze's goal areas over
    the wire (as JSON, made ``Area``s again): ``InRegion: {}`` reads them there as in a run of its
    own. The micromouse maze's goal is its centre; the robot starts in a corner."""
    assignment = tmp_path / "a.yaml"
    assignment.write_text(
        "name: goal\nvariants:\n  - {name: mouse, maze: micromouse_4x4, start: start, seeds: 1, noise: off}\n"
        "criteria:\n  - {name: ends well, points: 1, finishes: true}\n"
        "palette: {plugins: true}\nlimits: {cpu: 10s, wall: 600s, memory: 1024}\n"
    )
    folder = tmp_path / "mouse"
    folder.mkdir()
    (folder / "nodes.py").write_text(
        "from py_trees.common import Status\nfrom thymio_bt.behaviours import RobotBehaviour\n"
        "class Go(RobotBehaviour):\n    '''Always done.'''\n    def step(self):\n        return Status.SUCCESS\n"
    )
    (folder / "m.yaml").write_text(
        "maze: micromouse_4x4\nstart: start\nplugins: [nodes.py]\ntree:\n  sequence:\n    children:\n"
        "      - Go\n      - invert: {do: {InRegion: {}}}\n"
    )
    (student,) = grade(assignment, [folder], workers=1).to_json()["students"]
    assert student["status"] == "graded", student["messages"]
    assert [(run["status"], run["code"]) for run in student["runs"]] == [("SUCCESS", None)], student["runs"]
