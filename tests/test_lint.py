"""thymio-bt lint: each rule found by a small mission that has the mistake and not by one without
it, at the mistake's line; the CLI's output and exit codes; the shipped missions; the examples of
docs/lint.md; --assignment's conditions never true and nodes never ticked."""

import re
import textwrap
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.analysis.lint import RULES, lint_mission
from thymio_bt.cli import main
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parent.parent
LINE = re.compile(r"^.+:\d+: \[[a-z-]+\] .+ \(hint: .+\)$")


def _write(tmp_path, tree, extra="", name="m.yaml"):
    path = tmp_path / name
    body = textwrap.indent(textwrap.dedent(tree).strip(), "  ")
    path.write_text(f"maze: arena\nstart: [0.45, 0.45, 0]\ntime_limit: 20\n{textwrap.dedent(extra)}tree:\n{body}\n")
    return path


def _found(tmp_path, tree, extra=""):
    """(line, rule) of each finding; the mission's first tree line is line 5 (6 after one extra line)."""
    return [(f.line, f.rule) for f in lint_mission(_write(tmp_path, tree, extra))]


def test_children_after_one_that_always_succeeds_in_a_selector_never_run(tmp_path):
    assert _found(tmp_path, "selector: [Stop, {MoveDistance: {distance: 10cm}}, Stop]") == [(5, "unreachable")]
    [finding] = lint_mission(tmp_path / "m.yaml")
    assert finding.message == (
        "'MoveDistance' never runs (nor the 1 after it): 'Stop' before it in selector 'selector' always succeeds"
    )
    assert _found(tmp_path, "selector: [{WallAhead: {}}, Stop]") == []


def test_children_after_one_that_always_fails_or_never_ends_in_a_sequence_never_run(tmp_path):
    tree = """
    sequence:
      - bt_always_failure
      - Stop
    """
    assert _found(tmp_path, tree) == [(7, "unreachable")]
    tree = """
    sequence:
      - repeat: {do: Stop}
      - Stop
    """
    found = _found(tmp_path, tree)
    assert (7, "unreachable") in found and (6, "forever") in found
    assert "never ends" in next(f.message for f in lint_mission(tmp_path / "m.yaml") if f.rule == "unreachable")
    assert _found(tmp_path, "sequence: [Stop, {MoveDistance: {distance: 10cm}}]") == []


def test_an_until_after_a_body_that_never_succeeds_and_a_guard_that_never_holds(tmp_path):
    tree = """
    repeat:
      until: WallAhead
      do: bt_always_failure
    """
    assert _found(tmp_path, tree) == [(6, "unreachable")]
    tree = """
    guard:
      condition: bt_always_failure
      do: Stop
    """
    assert _found(tmp_path, tree) == [(7, "unreachable")]
    tree = """
    guard:
      condition: {WallAhead: {}}
      do: {repeat: {until: WallAhead, do: {MoveDistance: {distance: 5cm}}}}
    """
    assert _found(tmp_path, tree) == []


def test_a_reactive_sequence_with_an_action_before_another_restarts_it_every_tick(tmp_path):
    tree = """
    reactive_sequence:
      - invert: {WallAhead: {distance: 5cm}}
      - MoveDistance: {distance: 10cm}
      - TurnAngle: {angle: 90deg}
    """
    assert _found(tmp_path, tree) == [(7, "reactive-restart")]
    # what the rule says happens: once TurnAngle runs, MoveDistance starts again at every tick
    result = Run(load_mission(tmp_path / "m.yaml"), 0).run()
    starts = [e["name"] for e in result.events if e["kind"] == "behaviour_start"]
    turns = [e["status"] for e in result.events if e["kind"] == "behaviour_end" and e["name"] == "TurnAngle"]
    assert starts.count("MoveDistance") > 5 and turns and set(turns) == {"INVALID"}  # halted, never done
    tree = """
    reactive_sequence:
      - invert: {WallAhead: {distance: 5cm}}
      - sequence: [{MoveDistance: {distance: 10cm}}, {TurnAngle: {angle: 90deg}}]
    """
    assert _found(tmp_path, tree) == []  # a condition, then the steps as one sequence: the intended use
    assert Run(load_mission(tmp_path / "m.yaml"), 0).run().status == "SUCCESS"
    tree = """
    bt_reactive_sequence:
      - MoveDistance: {distance: 10cm}
      - bt_sleep: {msec: 500}
    """
    assert _found(tmp_path, tree) == [(6, "reactive-restart")]


def test_a_reactive_selector_with_an_unguarded_action_first_restarts_it_every_tick(tmp_path):
    tree = """
    reactive_selector:
      - MoveUntilWall: {distance: 5cm}
      - TurnAngle: {angle: 90deg}
    """
    assert _found(tmp_path, tree) == [(6, "reactive-restart")]
    tree = """
    reactive_selector:
      - sequence: [{ObstacleAhead: {}}, {TurnAngle: {angle: 90deg}}]
      - MoveDistance: {distance: 10cm}
    """
    assert _found(tmp_path, tree) == []  # the higher priority begins with a condition


def test_a_repeat_forever_with_no_way_out(tmp_path):
    forever = "repeat: {do: {force_success: {MoveDistance: {distance: 5cm}}}}"
    assert _found(tmp_path, forever) == [(5, "forever")]
    assert _found(tmp_path, f"timeout: {{seconds: 30, do: {{{forever}}}}}") == []
    assert _found(tmp_path, "repeat: {do: {MoveDistance: {distance: 5cm}}}") == []  # it ends when its child fails
    tree = f"""
    parallel:
      policy: success_on_one
      children: [{{{forever}}}, {{Wait: {{seconds: 5}}}}]
    """
    assert _found(tmp_path, tree) == []
    tree = f"""
    reactive_sequence: [{{WallAhead: {{}}}}, {{{forever}}}]
    """
    assert _found(tmp_path, tree) == []  # the condition, checked at every tick, can stop it


@pytest.mark.parametrize("above", ["bt_force_success", "bt_force_failure", "bt_keep_running_until_failure", "bt_delay"])
def test_bt_cpp_s_decorators_that_cannot_stop_their_child_are_no_way_out_of_a_repeat_forever(tmp_path, above):
    """As their thymio-bt twins (force_success, delay...): they declare they never halt their child."""
    body = "{delay_msec: 10, do: LOOP}" if above == "bt_delay" else "{do: LOOP}"
    loop = "{repeat: {do: {force_success: {MoveDistance: {distance: 5cm}}}}}"
    assert _found(tmp_path, f"{above}: {body.replace('LOOP', loop)}") == [(5, "forever")]
    assert _found(tmp_path, f"bt_timeout: {{msec: 100, do: {loop}}}") == []  # a timeout stops it


def test_a_reactive_selector_s_bt_parallel_with_an_unguarded_action_restarts_it_every_tick(tmp_path):
    """BT.CPP's Parallel starts every child, as thymio-bt's parallel does: an action in any of them."""
    tree = """
    bt_reactive_fallback:
      - bt_parallel: [{WallAhead: {}}, {MoveUntilWall: {distance: 5cm}}]
      - TurnAngle: {angle: 90deg}
    """
    assert _found(tmp_path, tree) == [(6, "reactive-restart")]


def test_unused_subtrees_and_parameters(tmp_path):
    extra = """\
    parameters: {speed: 10cm/s, spare: 3}
    subtrees:
      used:
        parameters: {distance: 5cm, unused_here: 1}
        tree: {MoveDistance: {distance: $distance, speed: $speed}}
      forgotten:
        tree: Stop
    """
    found = _found(tmp_path, "used: {}", extra)
    assert found == [(4, "unused-parameter"), (7, "unused-parameter"), (9, "unused-subtree")]
    clean = """\
    parameters: {speed: 10cm/s}
    subtrees:
      used:
        parameters: {distance: 5cm}
        tree: {MoveDistance: {distance: $distance, speed: $speed}}
    """
    assert _found(tmp_path, "used: {distance: 4cm}", clean) == []


def test_an_included_file_none_of_whose_subtrees_is_used(tmp_path):
    (tmp_path / "lib.yaml").write_text("subtrees:\n  turn:\n    tree: {TurnAngle: {angle: 90deg}}\n")
    found = lint_mission(_write(tmp_path, "Stop", "include: lib.yaml\n"))
    assert [(f.line, f.rule) for f in found] == [(4, "unused-subtree")]
    assert "lib.yaml (turn)" in found[0].message
    assert _found(tmp_path, "turn: {}", "include: lib.yaml\n") == []


def test_values_at_the_edge_of_their_range(tmp_path):
    assert _found(tmp_path, "WallAhead: {distance: 9.5cm}") == [(5, "edge-of-range")]  # <= 9.75 cm
    [finding] = lint_mission(tmp_path / "m.yaml")
    assert "distance of 'WallAhead' is 0.095, at the edge of its range (<= 0.0975)" in finding.message
    assert _found(tmp_path, "MoveDistance: {distance: 10cm, speed: 19.5cm/s}") == [(5, "edge-of-range")]
    assert _found(tmp_path, "WallAhead: {distance: 8cm}") == []
    assert _found(tmp_path, "WallAhead") == []  # a default is not written: not the student's choice
    # a sensed length's bound is the mission's robot's range: Enki's sensors read to 14 cm
    assert _found(tmp_path, "WallAhead: {distance: 9.5cm}", "robot: enki\n") == []
    assert _found(tmp_path, "WallAhead: {distance: 13.5cm}", "robot: enki\n") == [(6, "edge-of-range")]


def test_the_cli_prints_one_finding_per_line_and_exits_1_0_or_2(tmp_path):
    bad = _write(tmp_path, "selector: [Stop, Stop]")
    result = CliRunner().invoke(main, ["lint", str(bad)])
    assert result.exit_code == 1
    assert result.output.splitlines()[0] == (
        f"{bad}:5: [unreachable] 'Stop#2' never runs: 'Stop' before it in selector 'selector' always succeeds "
        "(hint: a selector tries its next child only when one fails: put the child that always succeeds last)"
    )
    assert CliRunner().invoke(main, ["lint", str(_write(tmp_path, "Stop"))]).exit_code == 0
    (tmp_path / "broken.yaml").write_text("maze: arena\nstart: [0.45, 0.45, 0]\ntree: {MoveUntilWal: {}}\n")
    broken = CliRunner().invoke(main, ["lint", str(tmp_path / "broken.yaml")])
    assert broken.exit_code == 2 and "broken.yaml:3" in broken.output and "Traceback" not in broken.output


def test_lint_does_not_run_a_mission_s_plugins(tmp_path):
    (tmp_path / "spin.py").write_text(
        "import os\nos.abort()\nfrom thymio_bt.behaviours import RobotBehaviour\n"
        "class Spin(RobotBehaviour):\n    pass\n"
    )
    path = _write(tmp_path, "sequence: [Spin, Stop]", "plugins: [spin.py]\n")
    assert lint_mission(path) == []  # os.abort() would have ended the test


@pytest.mark.parametrize("path", sorted((ROOT / "missions").glob("*.yaml")), ids=lambda p: p.stem)
def test_the_shipped_missions_lint_clean_but_the_fast_run_at_full_speed(path):
    found = [(f.rule, f.message) for f in lint_mission(path)]
    if path.stem == "micromouse":  # the fast run drives at MoveCells' top speed on purpose
        message = "speed of 'MoveCells' in 'fast run' is 0.2, at the edge of its range (<= 0.2)"
        assert found == [("edge-of-range", message)]
    else:
        assert found == []


def _doc_examples():
    page = (ROOT / "docs" / "lint.md").read_text()
    return re.findall(r"```yaml\n# lint: ([a-z-]+)\n(.*?)```", page, flags=re.S)


def test_docs_lint_has_an_example_of_every_static_rule():
    shown = {rule for rule, _ in _doc_examples()}
    assert shown >= set(RULES) - {"never-true", "never-ticked"} and "clean" in shown


@pytest.mark.parametrize("rule, text", _doc_examples(), ids=lambda v: v if v in (*RULES, "clean") else "")
def test_each_example_of_docs_lint_finds_what_it_says(tmp_path, rule, text):
    path = tmp_path / "example.yaml"
    path.write_text(text)
    found = {f.rule for f in lint_mission(path)}
    assert found == (set() if rule == "clean" else {rule})


ASSIGNMENT = """\
name: t
variants:
  - {name: part1, maze: two_parts_maze, start: part1}
  - {name: part2, maze: two_parts_maze, start: part2}
criteria:
  - {name: never touches a wall, points: 1, no_collision: true}
"""


def test_assignment_finds_conditions_never_true_and_nodes_never_ticked(tmp_path):
    (tmp_path / "a.yaml").write_text(ASSIGNMENT)
    path = tmp_path / "m.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            maze: two_parts_maze
            start: part1
            time_limit: 30
            tree:
              sequence:
                - selector:
                    - sequence: [{ObstacleAhead: {}}, {TurnAngle: {angle: 180deg}}]
                    - MoveUntilWall: {distance: 5cm}
                - selector:
                    - WallAhead: {distance: 9cm}
                    - Stop
            """
        )
    )
    result = CliRunner().invoke(main, ["lint", str(path), "--assignment", str(tmp_path / "a.yaml")])
    assert result.exit_code == 1, result.output
    lines = result.output.splitlines()
    assert all(LINE.match(line) for line in lines[:-1])
    assert [line.split(": [")[1].split("]")[0] for line in lines[:-1]] == ["never-true", "never-ticked", "never-ticked"]
    assert lines[0].startswith(f"{path}:7: [never-true] condition 'ObstacleAhead' was never true in 2 runs (2 checks)")
    assert lines[1].startswith(f"{path}:7: [never-ticked] 'TurnAngle' never ran in 2 runs")
    assert lines[2].startswith(f"{path}:11: [never-ticked] 'Stop' never ran")  # the wall ahead: true each time
    without = CliRunner().invoke(main, ["lint", str(path)])
    assert without.exit_code == 0, without.output


def test_a_broken_assignment_is_a_user_error(tmp_path):
    (tmp_path / "a.yaml").write_text("name: t\nvariants: []\n")
    result = CliRunner().invoke(main, ["lint", "square", "--assignment", str(tmp_path / "a.yaml")])
    assert result.exit_code == 2 and "a.yaml" in result.output


def test_lint_without_assignment_loads_no_physics_engine():
    import subprocess
    import sys

    code = (
        "import sys\nfrom thymio_bt.cli import main\nsys.argv = ['thymio-bt', 'lint', 'missions/maze_bonus.yaml']\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        "print('pymunk' in sys.modules, any(m.startswith('thymio_bt.backends.') for m in sys.modules), file=sys.stderr)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "False False"


def test_standard_output_holds_the_findings_only_and_a_shipped_assignment_is_found_by_name():
    clean = CliRunner().invoke(main, ["lint", "square"])
    assert (clean.exit_code, clean.stdout, clean.stderr) == (0, "", "square: no findings\n")
    ada = str(ROOT / "examples/class/ada/part1_2.yaml")
    by_name = CliRunner().invoke(main, ["lint", ada, "--assignment", "course_part1_2"])  # its mazes are beside it
    assert (by_name.exit_code, by_name.stdout, by_name.stderr) == (0, "", "part1_2: no findings\n")


@pytest.mark.parametrize(
    "tree",
    [
        "sequence: [invert: {WallAhead: {distance: 8cm}}, MoveDistance: {distance: 1m}]",
        "bt_sequence: [invert: ObstacleAhead, Stop, repeat: {times: 3, do: {MoveDistance: {distance: 20cm}}}]",
        "sequence: [invert: {WallAhead: {distance: 5cm}}, sequence: [GoToPose: {goal: [1.0, 0.45]}, Stop]]",
    ],
)
def test_a_way_ahead_checked_once_before_a_longer_drive(tmp_path, tree):
    """issue 46 item 6: docs/control_nodes.md's classic mistake, found at the condition's line."""
    assert _found(tmp_path, tree) == [(5, "checked-once")]


@pytest.mark.parametrize(
    "tree",
    [
        "reactive_sequence: [invert: {WallAhead: {distance: 8cm}}, MoveDistance: {distance: 1m}]",  # the fix
        "guard: {condition: {invert: WallAhead}, do: {MoveDistance: {distance: 1m}}}",
        "sequence: [SideOpen: {side: left}, TurnAngle: {angle: 90deg}]",  # a decision, then a turn
        "sequence: [invert: {WallAhead: {distance: 9cm}}, MoveDistance: {distance: 5cm}]",  # within the clearance
        "sequence: [invert: {WallAhead: {distance: 8cm}}, MoveUntilWall: {distance: 5cm}]",  # stops itself
        "sequence: [WallAhead: {distance: 8cm}, MoveDistance: {distance: -20cm}]",  # backs away from it
        "sequence: [invert: ObstacleAhead, SetBlackboard: {key: k, value: 0}]",
    ],
)
def test_a_condition_in_a_sequence_used_as_meant_is_not_checked_once(tmp_path, tree):
    assert "checked-once" not in {rule for _, rule in _found(tmp_path, tree)}


def _shipped_and_documented():
    """The missions a student is shown: examples, the example submissions of the assignments, and
    the examples of docs/control_nodes.md (by their name: line)."""
    files = sorted((ROOT / "examples").rglob("*.yaml"))
    blocks = re.findall(r"```yaml\n# result: [^\n]*\n(.*?)```", (ROOT / "docs" / "control_nodes.md").read_text(), re.S)
    return [*files, *blocks]


def test_checked_once_finds_only_the_classic_mistake_of_the_shipped_and_documented_missions(tmp_path):
    """The intended uses of the shipped files (missions/ are linted above) are not found; of
    docs/control_nodes.md's examples only unguarded_drive, which shows the mistake, is."""
    found = []
    for i, item in enumerate(_shipped_and_documented()):
        path = item if isinstance(item, Path) else tmp_path / f"doc{i}.yaml"
        if not isinstance(item, Path):
            path.write_text(item)
        try:
            findings = lint_mission(path)
        except Exception:  # a deliberately broken example submission (eve's misspelt node)
            continue
        found += [re.search(r"name: (\w+)", path.read_text())[1] for f in findings if f.rule == "checked-once"]
    assert found == ["unguarded_drive"]
