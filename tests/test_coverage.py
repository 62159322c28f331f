"""Tree coverage (thymio_bt.run.coverage): every node of the plan counted however it is ticked, the
child that ended each composite, merging over runs and processes, and run/sweep --coverage whose
reports keep the contract's keys and order and add "coverage" only when asked."""

import json
import textwrap
from pathlib import Path

import _require
import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.mission import load_mission
from thymio_bt.run.coverage import Coverage, NodeTable, plan_paths
from thymio_bt.run.runner import Run
from thymio_bt.run.sweep import Job, LocalPool, run_job, sweep
from thymio_bt.viz.graph import coverage_dot
from thymio_bt.viz.terminal import coverage_text

ROOT = Path(__file__).resolve().parents[1]

KEYS = ["path", "name", "kind", "behaviour", "where", "depth", "ticks", "success", "failure", "running", "ended_by"]


def _mission(tmp_path, tree, name="m.yaml", time_limit=30):
    path = tmp_path / name
    body = textwrap.indent(textwrap.dedent(tree).strip(), "  ")
    path.write_text(f"maze: arena\nstart: [0.45, 0.45, 0]\ntime_limit: {time_limit}\ntree:\n{body}\n")
    return load_mission(path)


def _covered(mission, seed=0):
    result = Run(mission, seed, node_stats=True).run()
    return result, Coverage.of(mission.tree).add(result.node_stats).to_json()


def _by_path(data):
    return {n["path"]: n for n in data["nodes"]}


def test_coverage_of_a_plan_lists_every_node_in_pre_order_with_its_place_and_depth():
    mission = load_mission("maze_part1_2")
    data = Coverage.of(mission.tree).to_json()
    assert data["runs"] == 0
    assert [n["path"] for n in data["nodes"]] == [path for _, path, _ in plan_paths(mission.tree)]
    assert len(data["nodes"]) == len(list(mission.tree.walk())) == len(data["never_ticked"])
    first, part1 = data["nodes"][:2]
    assert list(first) == KEYS
    assert (first["path"], first["kind"], first["depth"], first["behaviour"]) == ("course", "sequence", 0, None)
    assert (part1["path"], part1["behaviour"], part1["depth"]) == ("course/part 1", "MoveUntilWall", 1)
    assert part1["where"].endswith("maze_part1_2.yaml:32")


def test_a_run_counts_ticks_results_and_the_child_that_ended_each_composite():
    mission = load_mission("maze_bonus")
    result, data = _covered(mission)
    nodes = _by_path(data)
    assert data["runs"] == 1 and data["never_ticked"] == []
    root = nodes["bonus maze"]
    assert root["ticks"] == result.ticks and root["success"] == 1  # the root is ticked every tick
    for node in data["nodes"]:
        assert node["ticks"] == node["success"] + node["failure"] + node["running"], node["path"]
    # the selector at each wall: the dead-end check ended it once, the turn at every other wall
    selector = nodes["bonus maze/leg/stop or turn"]
    dead_end = nodes["bonus maze/leg/stop or turn/IsDeadEnd"]
    assert selector["ended_by"] == {
        "bonus maze/leg/stop or turn/turn": dead_end["failure"],
        "bonus maze/leg/stop or turn/IsDeadEnd": 1,
    }
    assert (dead_end["success"], dead_end["failure"]) == (1, 11)  # a condition: true once, false 11 times
    assert root["ended_by"] == {"bonus maze/IsDeadEnd": 1}  # the loop's until condition ended it
    # the legacy table keeps its rows as they were
    assert result.node_stats["bonus maze"] == {
        "ticks": result.ticks,
        "successes": 1,
        "failures": 0,
        "running_time": pytest.approx((result.ticks - 1) * 0.1),
    }


def test_counting_changes_nothing_in_the_run():
    mission = load_mission("maze_part1_2", {"noise.wheel": "0.03", "noise.odometry": "0.01"})
    plain, counted = Run(mission, 3).run().report(), Run(mission, 3, node_stats=True).run().report()
    for report in (plain, counted):
        del report["wall_time"], report["real_time_factor"]
    assert json.dumps(plain) == json.dumps(counted)


def test_nodes_that_never_run_are_listed_and_a_parallel_is_ended_by_its_failing_child(tmp_path):
    mission = _mission(
        tmp_path,
        """
        sequence:
          name: root
          children:
            - selector: [Stop, {MoveDistance: {distance: 10cm}}]
            - force_success:
                parallel:
                  name: both
                  children: [{Wait: {seconds: 1}}, bt_always_failure]
        """,
    )
    _, data = _covered(mission)
    nodes = _by_path(data)
    assert data["never_ticked"] == ["root/selector/MoveDistance"]
    assert nodes["root/selector"]["ended_by"] == {"root/selector/Stop": 1}
    assert nodes["root/force_success/both"]["ended_by"] == {"root/force_success/both/bt_always_failure": 1}
    assert nodes["root/force_success/both/Wait"]["running"] == 1  # ticked once, then halted


def test_a_guard_s_condition_is_counted_under_its_guard(tmp_path):
    mission = _mission(
        tmp_path,
        """
        force_success:
          guard:
            name: g
            condition: {invert: {WallAhead: {distance: 8cm}}}
            do: {MoveDistance: {distance: 1m}}
        """,
    )
    result, data = _covered(mission)
    nodes = _by_path(data)
    wall = nodes["force_success/g/invert/WallAhead"]
    assert wall["ticks"] == nodes["force_success/g"]["ticks"] == result.ticks  # checked at every tick
    assert (wall["success"], wall["failure"]) == (1, result.ticks - 1)  # true once: the wall came near
    assert nodes["force_success/g"]["ended_by"] == {"force_success/g/invert": 1}
    assert nodes["force_success/g/MoveDistance"]["ticks"] == result.ticks - 1  # not when the guard failed


def test_bt_cpp_nodes_count_each_execute_tick(tmp_path):
    mission = _mission(
        tmp_path,
        """
        bt_reactive_sequence:
          name: bt
          children: [bt_always_success, {bt_sleep: {msec: 300}}]
        """,
    )
    result, data = _covered(mission)
    nodes = _by_path(data)
    assert result.ticks == 4
    assert nodes["bt/bt_always_success"]["ticks"] == 4  # a reactive sequence re-ticks it every tick
    assert (nodes["bt/bt_sleep"]["running"], nodes["bt/bt_sleep"]["success"]) == (3, 1)
    assert nodes["bt"]["ended_by"] == {"bt/bt_sleep": 1}


def test_a_do_and_an_until_of_one_name_are_two_nodes(tmp_path):
    mission = _mission(
        tmp_path,
        """
        repeat:
          name: loop
          until: bt_always_success
          do: bt_always_success
        """,
    )
    _, data = _covered(mission)
    nodes = _by_path(data)
    assert list(nodes) == ["loop", "loop/bt_always_success", "loop/bt_always_success#2"]
    assert nodes["loop"]["ended_by"] == {"loop/bt_always_success#2": 1}


def test_coverages_add_merge_and_round_trip_through_json():
    mission = load_mission("square")
    tables = [Run(mission, seed, node_stats=True).run().node_stats for seed in (0, 1)]
    both = Coverage.of(mission.tree).add(tables[0]).add(tables[1]).to_json()
    one = Coverage.of(mission.tree).add(tables[0]).to_json()
    merged = Coverage.from_json(one).merge(Coverage.of(mission.tree).add(tables[1]).to_json()).to_json()
    assert merged == both and both["runs"] == 2
    assert Coverage.from_json(json.loads(json.dumps(both))).to_json() == both
    assert both["nodes"][0]["ticks"] == one["nodes"][0]["ticks"] + tables[1]["four sides"]["ticks"]
    # a plain dict of rows (no NodeTable detail): running is what is left of the ticks
    plain = Coverage.of(mission.tree).add(dict(tables[0])).to_json()
    assert [n["running"] for n in plain["nodes"]] == [n["running"] for n in one["nodes"]]
    assert isinstance(tables[0], NodeTable) and Coverage.of(mission.tree).add(None).runs == 0


def test_a_table_s_rows_keep_the_ended_by_through_json():
    mission = load_mission("maze_bonus")
    table = Run(mission, 0, node_stats=True).run().node_stats
    full = Coverage.of(mission.tree).add(table).to_json()
    assert Coverage.of(mission.tree).add(json.loads(json.dumps(table.rows()))).to_json() == full
    lost = Coverage.of(mission.tree).add(json.loads(json.dumps(table))).to_json()  # JSON drops the detail
    assert lost["nodes"][0]["ended_by"] == {} and full["nodes"][0]["ended_by"] == {"bonus maze/IsDeadEnd": 1}


def test_run_coverage_adds_the_key_last_and_only_when_asked(tmp_path):
    plain, covered = tmp_path / "plain.json", tmp_path / "covered.json"
    assert CliRunner().invoke(main, ["run", "square", "--report", str(plain)]).exit_code == 0
    result = CliRunner().invoke(main, ["run", "square", "--report", str(covered), "--coverage"])
    assert result.exit_code == 0, result.output
    before, after = json.loads(plain.read_text()), json.loads(covered.read_text())
    assert "coverage" not in before and list(after) == [*before, "coverage"]
    assert after["coverage"]["runs"] == 1 and after["coverage"]["never_ticked"] == []
    lines = result.output.splitlines()
    at = lines.index("tree coverage over 1 run: 4 of 4 nodes ticked")
    assert lines[at - 1].startswith("  collisions:")  # after the summary
    assert lines[at + 1].startswith("-^- four sides") and lines[at + 1].endswith("ended by side x1")


def test_coverage_tree_draws_a_dot_and_refuses_an_unknown_suffix(tmp_path):
    dot = tmp_path / "cov.dot"
    result = CliRunner().invoke(main, ["run", "square", "-q", "--coverage-tree", str(dot)])
    assert result.exit_code == 0, result.output
    text = dot.read_text()
    assert text.startswith("digraph coverage {") and text.count(" -> ") == 3 and "ended it x4" in text
    bad = CliRunner().invoke(main, ["run", "square", "--coverage-tree", str(tmp_path / "cov.txt")])
    assert bad.exit_code == 2 and "end the name with .dot, .svg or .png" in bad.output
    assert not (tmp_path / "cov.txt").exists()


def test_coverage_tree_draws_an_svg_with_graphviz(tmp_path):
    _require.program("dot")  # Graphviz draws the .svg: CI installs it (.ci/setup.d/10-graphviz.sh)
    svg = tmp_path / "cov.svg"
    assert CliRunner().invoke(main, ["run", "square", "-q", "--coverage-tree", str(svg)]).exit_code == 0
    assert "<svg" in svg.read_text()


def test_sweep_coverage_is_merged_over_the_runs_and_only_when_asked(tmp_path):
    out, plain = tmp_path / "s.json", tmp_path / "p.json"
    args = ["sweep", f"{ROOT}/missions/square.yaml", "--runs", "3", "--workers", "2"]
    result = CliRunner().invoke(main, [*args, "--out", str(out), "--coverage"])
    assert result.exit_code == 0, result.output
    assert CliRunner().invoke(main, [*args, "--out", str(plain)]).exit_code == 0
    data, before = json.loads(out.read_text()), json.loads(plain.read_text())
    assert list(data) == [*before, "coverage"] and "coverage" not in before
    assert data["coverage"]["runs"] == 3 and all("coverage" not in r for r in data["results"])
    assert data["coverage"]["nodes"][0]["success"] == 3
    assert "tree coverage over 3 runs: 4 of 4 nodes ticked" in result.output
    matrix = CliRunner().invoke(main, [*args, "--coverage", "--matrix", "robot=course,enki"])
    assert matrix.exit_code == 2 and "not a --matrix" in matrix.output


def test_a_job_brings_its_coverage_back_only_when_asked():
    assert "coverage" not in run_job(Job(f"{ROOT}/missions/square.yaml", 0))
    summary = run_job(Job(f"{ROOT}/missions/square.yaml", 0, coverage=True))
    assert summary["coverage"]["runs"] == 1 and summary["coverage"]["nodes"][0]["path"] == "four sides"
    result = sweep(f"{ROOT}/missions/square.yaml", 2, executor=LocalPool(1), coverage=True)
    assert result.coverage is not None and result.coverage["runs"] == 2
    assert sweep(f"{ROOT}/missions/square.yaml", 1, executor=LocalPool(1)).coverage is None


def test_the_coverage_tree_says_true_and_false_for_conditions_and_marks_nodes_never_run(tmp_path):
    mission = _mission(tmp_path, "selector: [{WallAhead: {distance: 2cm}}, Stop, {Wait: {seconds: 1}}]")
    _, data = _covered(mission)
    text = coverage_text(data, conditions={"WallAhead"})
    lines = [" ".join(line.split()) for line in text.splitlines()]
    assert lines[2] == "--> WallAhead 1 tick: true 0, false 1 (never true)"
    assert lines[-1] == "--> Wait never ticked"
    dot = coverage_dot(data, conditions={"WallAhead"})
    assert "color=red" in dot and "style=dashed" in dot


def test_tree_shows_the_coverage_a_report_holds_and_refuses_another_tree_s(tmp_path):
    report, dot = tmp_path / "r.json", tmp_path / "c.dot"
    assert CliRunner().invoke(main, ["run", "square", "-q", "--coverage", "--report", str(report)]).exit_code == 0
    shown = CliRunner().invoke(
        main, ["tree", f"{ROOT}/missions/square.yaml", "--coverage", str(report), "-o", str(dot)]
    )
    assert shown.exit_code == 0, shown.output
    assert shown.output.startswith("tree coverage over 1 run: 4 of 4 nodes ticked\n-^- four sides")
    assert dot.read_text().startswith("digraph coverage {") and "ended it x4" in dot.read_text()
    other = CliRunner().invoke(main, ["tree", f"{ROOT}/missions/maze_part1_2.yaml", "--coverage", str(report)])
    assert other.exit_code == 2 and "its coverage is of another tree" in other.output
    plain = tmp_path / "plain.json"
    assert CliRunner().invoke(main, ["run", "square", "-q", "--report", str(plain)]).exit_code == 0
    none = CliRunner().invoke(main, ["tree", f"{ROOT}/missions/square.yaml", "--coverage", str(plain)])
    assert none.exit_code == 2 and "holds no tree coverage" in none.output and "--coverage --report" in none.output
