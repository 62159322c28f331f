"""Broken missions and mazes: every problem at its exact file:line:col, with a hint, all at once.

Each file of ``tests/broken/`` (missions) and ``tests/broken/mazes/`` (mazes) starts with one
``# expect:`` line per problem, in the order they are reported::

    # expect: [FILE:]LINE:COL MESSAGE FRAGMENT [| hint: HINT FRAGMENT]

``FILE`` (relative to the broken file) is given when the problem is in another file (an included
file, the mission's maze). A problem that has a hint must name a fragment of it, and one without a
hint must not. ``tests/broken/lib/`` holds files that cases include; they are not cases themselves.
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import py_trees
import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.errors import Problem, UserError
from thymio_bt.maze import load_maze
from thymio_bt.mission import load_mission

ROOT = Path(__file__).resolve().parents[1]
BROKEN = Path(__file__).resolve().parent / "broken"
MISSION_CASES = sorted(BROKEN.glob("*.yaml"))
MAZE_CASES = sorted((BROKEN / "mazes").glob("*.yaml"))
CASES = MISSION_CASES + MAZE_CASES
MISSIONS = sorted((ROOT / "missions").glob("*.yaml"))

_EXPECT = re.compile(
    r"# expect: (?:(?P<file>[^\s:]+):)?(?P<line>\d+):(?P<col>\d+) (?P<message>.+?)"
    r"(?: \| hint: (?P<hint>.+))?"
)
_CLI_ERROR = re.compile(r"error: (?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<message>.*)")


@dataclass(frozen=True)
class Expected:
    """One expected problem, read from a ``# expect:`` line."""

    file: Path
    line: int
    col: int
    message: str
    hint: str | None


def case_id(path: Path) -> str:
    return str(path.relative_to(BROKEN))


def expectations(path: Path) -> list[Expected]:
    """The ``# expect:`` lines at the top of ``path``; a malformed one is an error, not skipped."""
    out = []
    for text in path.read_text(encoding="utf-8").splitlines():
        if not text.startswith("# expect"):
            break
        match = _EXPECT.fullmatch(text.rstrip())
        assert match, f"{path.name}: malformed expectation {text!r}"
        file = (path.parent / match["file"]).resolve() if match["file"] else path.resolve()
        out.append(Expected(file, int(match["line"]), int(match["col"]), match["message"], match["hint"]))
    return out


def load(path: Path) -> object:
    return load_maze(path) if path.parent.name == "mazes" else load_mission(path)


def check_problem(problem: Problem, want: Expected, case: str) -> None:
    got = f"{problem.file}:{problem.line}:{problem.column}: {problem.message} (hint: {problem.hint!r})"
    assert Path(problem.file).resolve() == want.file, f"{case}: wrong file: {got}"
    assert (problem.line, problem.column) == (want.line, want.col), f"{case}: wrong place: {got}"
    assert want.message in problem.message, f"{case}: wrong message: {got}"
    if want.hint is None:
        assert not problem.hint, f"{case}: a hint that the expectation does not name: {got}"
    else:
        assert want.hint in problem.hint, f"{case}: wrong or missing hint: {got}"


def check_case(path: Path) -> list[Problem]:
    """Load ``path`` and compare every reported problem with its expectation, in order."""
    expected = expectations(path)
    assert expected, f"{path.name} has no '# expect: LINE:COL MESSAGE' line"
    with pytest.raises(UserError) as info:
        load(path)
    problems = info.value.problems
    listing = "\n".join(str(p) for p in problems)
    assert len(problems) == len(expected), f"{path.name}: expected {len(expected)} problems, got:\n{listing}"
    for problem, want in zip(problems, expected, strict=True):
        check_problem(problem, want, path.name)
    return problems


# ------------------------------------------------------------------------------------- the corpus


def test_the_corpus_is_large_enough() -> None:
    assert len(MISSION_CASES) >= 30 and len(MAZE_CASES) >= 5


@pytest.mark.parametrize("path", CASES, ids=case_id)
def test_broken_file_reports_the_exact_place_message_and_hint(path: Path) -> None:
    check_case(path)


def test_a_case_without_expectation_fails(tmp_path: Path) -> None:
    case = tmp_path / "no_expectation.yaml"
    case.write_text((BROKEN / "typo_behaviour.yaml").read_text().split("\n", 1)[1])
    with pytest.raises(AssertionError, match="has no '# expect"):
        check_case(case)


@pytest.mark.parametrize(
    "wrong",
    [
        "7:8 unknown node type",
        "8:7 unknown node type",
        "7:7 unknown behaviour",
        "7:7 unknown node type | hint: did you mean 'MoveDistance'?",
        "7:7 unknown node type 'MoveUntilWal'",
    ],
)  # the hint is not named
def test_a_wrong_expectation_fails(tmp_path: Path, wrong: str) -> None:
    lines = (BROKEN / "typo_behaviour.yaml").read_text().split("\n")
    case = tmp_path / "typo_behaviour.yaml"
    case.write_text("\n".join([f"# expect: {wrong}", *lines[1:]]))
    with pytest.raises(AssertionError):
        check_case(case)


def test_a_malformed_expectation_fails(tmp_path: Path) -> None:
    case = tmp_path / "malformed.yaml"
    case.write_text("# expect: line 7 unknown node type\n" + (BROKEN / "typo_behaviour.yaml").read_text())
    with pytest.raises(AssertionError, match="malformed"):
        check_case(case)


def test_every_problem_of_a_file_is_reported_at_once() -> None:
    problems = check_case(BROKEN / "many_errors_everywhere.yaml")
    # six independent mistakes, from the start pose to the tree, each at its own line, in reading order
    lines = [p.line for p in problems]
    assert len(problems) == 6 and lines == sorted(set(lines))
    assert {p.path.split(".")[0].split("[")[0] for p in problems} >= {"start", "time_limit", "include", "tree"}
    assert len(check_case(BROKEN / "many_errors.yaml")) == 4


def test_problems_of_one_behaviour_are_all_reported() -> None:
    # an unknown key does not hide a range error of the same node
    with pytest.raises(UserError) as info:
        load_mission(BROKEN / "many_errors.yaml", overrides={"cruise": "5 m/s"})
    speed = [p for p in info.value.problems if p.path.endswith("MoveDistance.speed")]
    assert len(speed) == 1 and "less than or equal to 0.2" in speed[0].message, info.value


def test_overrides_are_checked_like_the_file() -> None:
    with pytest.raises(UserError) as info:
        load_mission(ROOT / "missions" / "maze_part1_2.yaml", overrides={"crusie": "0.15", "final_stop": "5deg"})
    problems = {p.message: p for p in info.value.problems}
    assert problems["no such parameter 'crusie'"].hint == "did you mean 'cruise'?"
    assert any("expected a length" in m for m in problems), list(problems)
    assert all(p.file == "--set" for p in problems.values())


def test_a_noise_override_is_said_at_set_not_at_the_mission() -> None:
    with pytest.raises(UserError) as info:
        load_mission(ROOT / "missions" / "square.yaml", overrides={"noise.wheeel": "0.1", "noise.range_sd": "9"})
    assert sorted((p.file, p.path) for p in info.value.problems) == [
        ("--set", "noise.range_sd"),
        ("--set", "noise.wheeel"),
    ]


def test_a_set_value_out_of_range_is_said_at_set_with_the_file_s_hint() -> None:
    """``--set cruise=10`` is the same mistake as ``speed: 10`` in the file: the same 'did you mean'
    hint, said once, at ``--set`` (not at the file's line that uses ``$cruise``)."""
    with pytest.raises(UserError) as info:
        load_mission(ROOT / "missions" / "maze_part1_2.yaml", overrides={"cruise": "10"})
    [problem] = info.value.problems  # three MoveUntilWall use $cruise: one fix
    assert (problem.file, problem.line) == ("--set", 0)
    assert problem.message.startswith("cruise=10: Input should be less than or equal to 0.2")
    assert problem.hint.startswith("did you mean 10cm/s? a bare number is in m/s")


def test_a_bare_number_parameter_used_as_a_speed_gets_the_unit_hint(tmp_path: Path) -> None:
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nparameters: {cruise: 10}\ntree: {MoveUntilWall: {speed: $cruise}}\n"
    )
    with pytest.raises(UserError) as info:
        load_mission(mission)
    [problem] = info.value.problems
    assert (problem.line, problem.hint.split("?")[0]) == (4, "did you mean 10cm/s")


@pytest.mark.parametrize(
    "args, said",
    [
        (["--robot", "missing.yaml"], "error: --robot: robot profile not found: missing.yaml [at robot]"),
        (["--set", "robot=missing.yaml"], "error: --set: robot profile not found: missing.yaml [at robot]"),
        (["--robot", "cours"], "error: --robot: robot must be one of course, enki, real"),
    ],
)
def test_a_bad_robot_is_said_at_the_option_that_gave_it(tmp_path: Path, args: list[str], said: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "run", "square", *args], cwd=tmp_path, capture_output=True, text=True
    )
    assert done.returncode == 2 and done.stderr.startswith(said), done.stderr
    assert "include file" not in done.stderr and "Traceback" not in done.stderr


SENSED = (
    "maze: arena\nstart: centre\n{robot}tree:\n  sequence:\n"
    "    - MoveUntilWall: {{distance: {stop}}}\n    - WallAhead: {{distance: {ahead}}}\n"
)


@pytest.mark.parametrize(
    "robot, stop, ahead, beyond",
    [
        ("course", "9.5cm", "9.75cm", []),
        (
            "course",
            "12cm",
            "9cm",
            [(6, "MoveUntilWall: distance 0.12 m is beyond the 'course' robot's sensor range (0.0975 m)")],
        ),
        (
            "real",
            "9.5cm",
            "9.5cm",
            [
                (6, "MoveUntilWall: distance 0.095 m is beyond the 'real' robot's sensor range (0.0933 m)"),
                (7, "WallAhead: distance 0.095 m is beyond the 'real' robot's sensor range (0.0933 m)"),
            ],
        ),
        ("enki", "12cm", "14cm", []),
    ],
)
def test_a_sensed_length_is_bounded_by_the_mission_s_robot(
    tmp_path: Path, robot: str, stop: str, ahead: str, beyond: list
) -> None:
    """A stop distance or a wall-ahead threshold must be one the robot's sensors can read: the course
    robot reads to 9.75 cm, a real Thymio to 9.33 cm, Enki's to 14 cm (the schema's bound)."""
    mission = tmp_path / "m.yaml"
    mission.write_text(SENSED.format(robot=f"robot: {robot}\n", stop=stop, ahead=ahead))
    if not beyond:
        assert load_mission(mission).robot == robot
        return
    with pytest.raises(UserError) as info:
        load_mission(mission)
    assert [(p.line, p.message) for p in info.value.problems] == beyond
    assert all("at most 0.09" in p.hint and "--robot enki: 0.14 m" in p.hint for p in info.value.problems)
    # the robots named are those that read that far: the course robot (9.75 cm) for 9.5 cm, not 12 cm
    assert all(("--robot course: 0.0975 m" in p.hint) == (robot == "real") for p in info.value.problems)


def test_a_sensed_length_beyond_the_robot_s_range_from_set_is_said_at_set(tmp_path: Path) -> None:
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nparameters: {stop: 5cm}\ntree: {MoveUntilWall: {distance: $stop}}\n"
    )
    with pytest.raises(UserError) as info:
        load_mission(mission, overrides={"stop": "12cm"})
    [problem] = info.value.problems
    assert (problem.file, problem.message) == (
        "--set",
        "stop=12cm: 0.12 m is beyond the 'course' robot's sensor range (0.0975 m)"
        " (where MoveUntilWall.distance uses it)",
    )
    assert "(--robot enki: 0.14 m)" in problem.hint  # the one robot that reads 12 cm
    assert load_mission(mission, overrides={"stop": "12cm", "robot": "enki"}).tree.params.distance == pytest.approx(
        0.12
    )


def test_enki_stops_at_a_distance_the_course_robot_cannot_read(tmp_path: Path) -> None:
    from thymio_bt.run.runner import Run

    mission = tmp_path / "m.yaml"
    mission.write_text(SENSED.format(robot="robot: enki\n", stop="12cm", ahead="13cm"))
    report = Run(load_mission(mission)).run().report()
    assert report["status"] == "SUCCESS"
    [stop] = [e for e in report["events"] if e["kind"] == "behaviour_end" and e["name"] == "MoveUntilWall"]
    assert stop["range"] == pytest.approx(0.12, abs=0.002)


REFERENCES = """\
maze: two_parts_maze
start: part1
parameters: {turn: bb:turn_angle, side: 20cm, where: part2}
subtrees:
  leg:
    parameters: {length: 10cm}
    tree: {MoveDistance: {distance: $length}}
tree:
  sequence:
    - TurnAngle: {angle: $turn}
    - leg: {length: $side}
    - SpawnEntity: {pose: $where}
    - leg: {length: $nope}
    - MoveDistance: {distance: $nope}
    - MoveDistance: {distance: $2cm}
"""


def test_a_parameter_reference_reads_the_same_in_every_place(tmp_path: Path) -> None:
    """``$name`` in a behaviour's parameter, a subtree's argument or a pose: the parameter's value
    (a bb: key stays a blackboard reference); an unknown name is the same problem everywhere, and
    ``$2cm`` (not a name) is a value for the unit parser."""
    mission = tmp_path / "refs.yaml"
    mission.write_text(REFERENCES)
    with pytest.raises(UserError) as info:
        load_mission(mission)
    in_tree = [(p.line, p.column, p.message, p.hint) for p in info.value.problems if p.line >= 13]
    assert in_tree == [
        (13, 21, "unknown parameter '$nope'", "expected one of: side, turn, where"),
        (14, 32, "unknown parameter '$nope'", "expected one of: side, turn, where"),
        (15, 32, "unexpected '$2cm' in '$2cm'", info.value.problems[-1].hint),
    ]
    assert info.value.problems[-1].hint.startswith("numbers may carry a unit")
    mission.write_text("\n".join(REFERENCES.splitlines()[:-3]))
    turn, leg, spawn = load_mission(mission).tree.children
    assert turn.blackboard_refs == {"angle": "turn_angle"} and turn.params.angle is None
    assert leg.subtree == "leg" and leg.params.distance == pytest.approx(0.2)
    assert spawn.params.pose == pytest.approx((0.5, 0.3, 1.5707963))


def test_an_impossible_start_override_is_reported_as_such() -> None:
    with pytest.raises(UserError) as info:
        load_mission(ROOT / "missions" / "maze_part1_2.yaml", start="0.3,0.2,0")
    [problem] = info.value.problems
    assert (problem.file, problem.message) == (
        "--start",
        "impossible start pose: pose (0.300, 0.200, yaw 0.000) overlaps a wall",
    )


def test_a_file_included_twice_is_read_once(tmp_path: Path) -> None:
    (tmp_path / "hop.yaml").write_text("subtrees:\n  hop:\n    tree: {MoveDistance: {distance: 5cm}}\n")
    (tmp_path / "a.yaml").write_text("include: hop.yaml\n")
    (tmp_path / "b.yaml").write_text("include: hop.yaml\n")
    (tmp_path / "mission.yaml").write_text(
        "maze: two_parts_maze\nstart: part1\ninclude: [a.yaml, b.yaml]\ntree: {sequence: [hop, hop]}\n"
    )
    mission = load_mission(tmp_path / "mission.yaml")
    assert [n.behaviour for n in mission.tree.walk() if n.kind == "behaviour"] == ["MoveDistance"] * 2


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        ("a: !!int abc", (1, 4), "invalid !!int value"),
        ("a: !!float x", (1, 4), "invalid !!float value"),
        ("a: " + "1" * 5000, (1, 4), "invalid !!int value"),
        ("a: &x [1, *x]", (1, 11), "the alias *x refers to the node that contains it"),
        ("a: " + "[" * 300 + "]" * 300, (1, 203), "nesting is deeper than 200 levels"),
        ("a: !!python/name:os.system", (1, 4), "the tag !!python/name:os.system is not allowed"),
        ("base: &b {x: 1}\nc:\n  <<: *b\n  x: 2\n  x: 3\n", (5, 3), "duplicate key 'x'"),
    ],
)
def test_yaml_that_python_cannot_hold_is_a_problem_at_its_place(
    text: str, where: tuple[int, int], message: str
) -> None:
    from thymio_bt.inputs.yamlio import loads_yaml

    with pytest.raises(UserError) as info:
        loads_yaml(text, "m.yaml")
    [problem] = info.value.problems
    assert (problem.file, problem.line, problem.column) == ("m.yaml", *where) and message in problem.message


def test_yaml_merge_keys_and_dates_are_plain_data() -> None:
    from thymio_bt.inputs.yamlio import loads_yaml

    assert loads_yaml("base: &b {x: 1, y: 2}\nc:\n  <<: *b\n  x: 3\n")["c"] == {"x": 3, "y": 2}
    assert loads_yaml("when: 2020-02-30") == {"when": "2020-02-30"}  # not a date, and not a crash


# ------------------------------------------------------------------------------------- the CLI


def _assert_cli_errors(stderr: str, path: Path) -> None:
    """stderr lists every expected problem as 'error: FILE:LINE:COL: message', with no traceback."""
    assert "Traceback" not in stderr
    found = [m for m in map(_CLI_ERROR.match, stderr.splitlines()) if m]
    expected = expectations(path)
    assert len(found) == len(expected), stderr
    for match, want in zip(found, expected, strict=True):
        got = Problem(match["message"], match["file"], int(match["line"]), int(match["col"]))
        assert Path(got.file).resolve() == want.file and (got.line, got.column) == (want.line, want.col), stderr
        assert want.message in got.message, stderr


@pytest.mark.parametrize("command", ["validate", "run"])
@pytest.mark.parametrize("path", MISSION_CASES, ids=case_id)
def test_cli_reports_broken_missions_with_exit_code_2(command: str, path: Path) -> None:
    result = CliRunner().invoke(main, [command, str(path)])
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    _assert_cli_errors(result.stderr, path)
    assert "Traceback" not in result.output


def _console_script() -> str:
    script = Path(sys.executable).with_name("thymio-bt")
    assert script.is_file(), f"the thymio-bt console script is not installed next to {sys.executable}"
    return str(script)


@pytest.mark.parametrize("command", ["validate", "run"])
def test_console_script_reports_a_broken_mission(command: str) -> None:
    path = BROKEN / "many_errors_everywhere.yaml"
    proc = subprocess.run([_console_script(), command, str(path)], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    _assert_cli_errors(proc.stderr, path)
    assert f"error: {path}:9:8: maze 'two_parts_maze' has no spawn named 'part_1' [at start]" in proc.stderr


def test_console_script_validates_the_course_missions() -> None:
    proc = subprocess.run(
        [_console_script(), "validate", *map(str, MISSIONS)], capture_output=True, text=True, timeout=60, cwd=ROOT
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("ok: ") == len(MISSIONS) and proc.stderr == ""


def test_validate_accepts_every_mission() -> None:
    assert len(MISSIONS) >= 5
    result = CliRunner().invoke(main, ["validate", *map(str, MISSIONS)])
    assert result.exit_code == 0, result.output
    assert result.output.count("ok: ") == len(MISSIONS)


def test_validate_checks_every_file_and_fails_if_one_is_broken() -> None:
    broken = BROKEN / "typo_behaviour.yaml"
    result = CliRunner().invoke(main, ["validate", str(MISSIONS[0]), str(broken), str(MISSIONS[1])])
    assert result.exit_code == 2
    assert result.stdout.count("ok: ") == 2
    assert f"error: {broken}:7:7: unknown node type 'MoveUntilWal'" in result.stderr


# ------------------------------------------------------------------------------------- no global state


def _blackboard_state() -> tuple[dict, dict, dict]:
    board = py_trees.blackboard.Blackboard
    return dict(board.storage), dict(board.clients), dict(board.metadata)


def test_loading_and_validating_leave_the_blackboard_empty() -> None:
    py_trees.blackboard.Blackboard.clear()
    for path in MISSIONS:
        mission = load_mission(path)
        assert mission.tree is not None
        assert _blackboard_state() == ({}, {}, {}), path
    for path in MISSION_CASES[:10]:
        with pytest.raises(UserError):
            load_mission(path)
    assert _blackboard_state() == ({}, {}, {})
    result = CliRunner().invoke(main, ["validate", *map(str, MISSIONS)])
    assert result.exit_code == 0
    assert _blackboard_state() == ({}, {}, {})


@pytest.mark.parametrize(
    "kind, hint",
    [
        ("Fallback", "Fallback is `selector` here"),
        ("Inverter", "Inverter is `invert` here"),
        ("IfThenElse", "IfThenElse is `bt_if_then_else` in YAML"),
    ],
)
def test_a_btcpp_node_name_in_yaml_says_what_it_is_called_here(tmp_path, kind, hint):
    path = tmp_path / "m.yaml"
    path.write_text(f"name: m\nmaze: two_parts_maze\nstart: part1\ntree:\n  {kind}:\n    - Stop: {{}}\n")
    with pytest.raises(UserError) as exc:
        load_mission(path)
    assert f"unknown node type '{kind}'" in str(exc.value) and hint in str(exc.value)


def test_validate_checks_a_mission_for_the_robot_given(tmp_path: Path) -> None:
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\ntree: {MoveUntilWall: {distance: 12cm}}\n")
    course = CliRunner().invoke(main, ["validate", str(mission)])
    assert course.exit_code == 2 and "beyond the 'course' robot's sensor range" in course.output
    assert CliRunner().invoke(main, ["validate", str(mission), "--robot", "enki"]).exit_code == 0


@pytest.mark.parametrize("robot", ["enkk", "missing.yaml"])
def test_a_refused_robot_is_the_one_problem_said(tmp_path: Path, robot: str) -> None:
    """Checks that need the robot are skipped, not made against the course robot in its place: a
    12 cm stop and a start against a wall said nothing more."""
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: [0.03, 0.5, 0]\ntree: {MoveUntilWall: {distance: 12cm}}\n")
    with pytest.raises(UserError) as info:
        load_mission(mission, overrides={"--robot": robot})
    [problem] = info.value.problems
    assert problem.file == "--robot" and robot in problem.message
