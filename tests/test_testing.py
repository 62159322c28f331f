"""The testing helpers users get: worlds, run_tree, node substitution, per-node statistics, plugin."""

from pathlib import Path

import py_trees
import pytest

from thymio_bt.robot.interface import Pose
from thymio_bt.testing import PRESETS, run_mission_file, world

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_presets_are_closed_worlds_with_a_start(preset):
    maze = world(preset)
    assert "start" in maze.spawns and maze.walls


def test_the_plugin_fixture_runs_a_behaviour_and_gives_node_statistics(thymio):
    result = thymio.run_tree(
        {"sequence": [{"MoveUntilWall": {"distance": "5cm"}}, {"TurnAngle": {"angle": "90deg"}}]},
        thymio.world("corridor"),
        seconds=30,
    )
    stats = result.node_stats
    assert stats["sequence/MoveUntilWall"]["successes"] == 1
    assert stats["sequence/MoveUntilWall"]["ticks"] == pytest.approx(
        stats["sequence/MoveUntilWall"]["running_time"] * 10 + 1
    )
    assert stats["sequence/TurnAngle"]["running_time"] > 1.0


def test_the_blackboard_starts_empty_in_every_test():
    assert py_trees.blackboard.Blackboard.storage == {}
    py_trees.blackboard.Blackboard.set("/left_over", 1)  # the next test must not see this


def test_the_blackboard_was_cleared_after_the_previous_test():
    assert "/left_over" not in py_trees.blackboard.Blackboard.storage


def test_substitution_replaces_nodes_by_path_pattern():
    skipped = run_mission_file(f"{ROOT}/missions/maze_part1_2.yaml", substitute={"course/part 2": "success"})
    assert skipped.status == "SUCCESS" and skipped.sim_time < 6
    assert skipped.final_pose == Pose(0.5, 0.3, 1.570796)


def test_a_scripted_stub_runs_for_simulated_seconds_then_returns_its_status():
    result = run_mission_file(
        f"{ROOT}/missions/maze_part1_2.yaml", substitute={"*/DeleteEntity": {"status": "success", "seconds": 2}}
    )
    # the real robot was never deleted, so the real spawn must refuse the taken name
    assert result.status == "FAILURE" and result.code == "ENTITY_ERROR"
    assert "already exists" in result.reason
    assert result.node_stats["course/DeleteEntity"]["running_time"] == pytest.approx(2.0)


def test_a_status_list_is_returned_one_per_tick():
    result = run_mission_file(
        f"{ROOT}/missions/square.yaml", substitute={"four sides/side/TurnAngle": ["running", "running", "failure"]}
    )
    assert result.status == "FAILURE"
    assert result.node_stats["four sides/side/TurnAngle"]["ticks"] == 3


def test_the_plugin_imports_nothing_heavy():
    import subprocess
    import sys

    code = (
        "import sys, thymio_bt.pytest_plugin; "
        "print(sorted(m for m in ('py_trees', 'pymunk', 'pydantic', 'numpy', 'thymio_bt.testing') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_the_plugin_leaves_the_blackboard_of_tests_that_made_no_behaviour(pytester):
    pytester.makepyfile("""
        import py_trees

        def test_a_writes():
            py_trees.blackboard.Blackboard.set("/mine", 1)

        def test_b_still_sees_it():
            assert py_trees.blackboard.Blackboard.get("/mine") == 1

        def test_c_makes_a_thymio_behaviour(thymio):
            thymio.run_tree({"Stop": {}}, thymio.world("corridor"))

        def test_d_the_blackboard_was_cleared_after_it():
            assert "/mine" not in py_trees.blackboard.Blackboard.storage
    """)
    pytester.runpytest_subprocess("-p", "no:cacheprovider").assert_outcomes(passed=4)


def test_a_substitution_that_matches_nothing_is_an_error_naming_it():
    from thymio_bt.errors import UserError

    with pytest.raises(UserError, match=r"substitution 'course/part2' matches no node .*did you mean 'course/part 2'"):
        run_mission_file(f"{ROOT}/missions/maze_part1_2.yaml", substitute={"course/part2": "success"})


def test_a_misspelt_preset_world_suggests_the_nearest():
    from thymio_bt.errors import UserError

    with pytest.raises(UserError, match="no preset world named 'coridor' .*did you mean 'corridor'"):
        world("coridor")


@pytest.mark.parametrize("key", ["maze_map", "my_map"])
def test_the_report_holds_the_map_where_the_mapping_behaviours_keep_it(key):
    """The run reads the map at the blackboard key its mapping behaviours were given."""
    from thymio_bt.testing import run_tree

    result = run_tree({"MapWalls": {"cell": 0.2, "key": key}}, world("corridor"), seconds=5)
    assert result.status == "SUCCESS"
    assert result.maze_map is not None and result.maze_map["visited"] == [[0, 0]] and result.maze_map["open_sides"] == 1
    assert result.report()["map"] == result.maze_map


def test_a_run_without_mapping_behaviours_reports_no_map():
    from thymio_bt.testing import run_tree

    result = run_tree({"SetBlackboard": {"key": "maze_map", "value": 3}}, world("corridor"), seconds=5)
    assert result.status == "SUCCESS" and result.maze_map is None and "map" not in result.report()


BACK_OFF = '''
from py_trees.common import Status
from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour


class BackOff(RobotBehaviour):
    """Reverse for a second."""

    yaml_name = "BackOff"
    Params = BehaviourParams
    moves = True

    def step(self):
        if self.elapsed() >= 1.0:
            return Status.SUCCESS
        self.robot.drive(-0.05, 0.0)
        return Status.RUNNING
'''


def test_run_tree_takes_plugins_relative_to_the_test_file_or_as_classes(pytester):
    """A newcomer's layout: the test and its plugins/ folder away from where pytest is started."""
    folder = pytester.mkpydir("students")
    (folder / "plugins").mkdir()
    (folder / "plugins" / "back_off.py").write_text(BACK_OFF)
    (folder / "test_back_off.py").write_text(
        "import importlib.util, pathlib\n"
        "from thymio_bt.testing import run_tree, world\n"
        "def test_a_relative_path(thymio):\n"
        "    result = thymio.run_tree('BackOff', world('arena'), plugins=['plugins/back_off.py'])\n"
        "    assert result.status == 'SUCCESS' and result.final_pose.x < 0.66\n"
        "def test_the_class_itself():\n"
        "    source = pathlib.Path(__file__).parent / 'plugins/back_off.py'\n"
        "    spec = importlib.util.spec_from_file_location('bo', source)\n"
        "    module = importlib.util.module_from_spec(spec)\n"
        "    spec.loader.exec_module(module)\n"
        "    assert run_tree('BackOff', world('arena'), plugins=[module.BackOff]).status == 'SUCCESS'\n"
        "def test_a_missing_file_says_where_it_looked():\n"
        "    import pytest\n"
        "    from thymio_bt.errors import UserError\n"
        "    with pytest.raises(UserError, match='relative to the calling test.s folder, .*students'):\n"
        "        run_tree('BackOff', world('arena'), plugins=['plugins/missing.py'])\n"
    )
    pytester.runpytest_subprocess("-p", "no:cacheprovider", "students").assert_outcomes(passed=3)


def test_a_bad_parameter_is_a_user_error_located_at_the_tests_own_line(thymio):
    """Not at the temporary mission file run_tree writes, which the test's author never sees."""
    from thymio_bt.errors import UserError
    from thymio_bt.testing import run_tree

    with pytest.raises(UserError) as err:
        run_tree({"sequence": [{"MoveUntilWall": {"distanse": "5cm"}}]}, world("corridor"))  # this line
    line = test_a_bad_parameter_is_a_user_error_located_at_the_tests_own_line.__code__.co_firstlineno + 6
    (problem,) = err.value.problems
    assert (problem.file, problem.line) == (__file__, line)
    assert str(err.value).startswith(f"{__file__}:{line}:1: MoveUntilWall has no parameter 'distanse'")
    assert problem.path == "tree.sequence[0].MoveUntilWall.distanse" and problem.hint == "did you mean 'distance'?"
    with pytest.raises(UserError) as err:
        thymio.run_tree({"TurnAngle": {"angle": 90}}, thymio.world("corridor"))  # the fixture's too
    assert err.value.problems[0].line == line + 7 and err.value.problems[0].file == __file__
