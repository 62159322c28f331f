"""Hostile BT.CPP XML missions: chains of subtrees thousands deep, subtrees that multiply, JSON
ports nested thousands deep, long scripts copied by subtrees: each is one located message
(file:line and a hint), exit 2, never a RecursionError, a traceback or a hang, and is refused fast."""

import signal
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

from thymio_bt.btcpp.xml_tree import MAX_JSON_NESTING, MAX_SUBTREE_DEPTH, MAX_TEXT
from thymio_bt.errors import UserError
from thymio_bt.plan.model import MAX_DEPTH, MAX_NODES

ROOT = Path(__file__).resolve().parents[1]

MAZE = (ROOT / "mazes/arena.yaml").resolve()
#: the CPU time one hostile file may cost (wall time varies with the machine's load, CPU time less)
BUDGET = 2.0


def _mission(tmp_path, main, trees="", settings=""):
    """An XML mission file: ``main`` the main tree's root, ``trees`` more <BehaviorTree>s, one per line."""
    path = tmp_path / "hostile.xml"
    path.write_text(
        f'<root BTCPP_format="4" main_tree_to_execute="Main">\n'
        f'<ThymioMission maze="{MAZE}" start="centre" time_limit="5"{settings}/>\n'
        f'<BehaviorTree ID="Main">{main}</BehaviorTree>\n{trees}</root>\n'
    )
    return path


@contextmanager
def _deadline(seconds=30):
    """Fail (rather than hang) when the block runs longer than ``seconds``."""

    def expired(*_):
        raise TimeoutError(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _refused(path):
    """The one problem loading ``path`` raises, checked to cost less than BUDGET s of CPU time;
    and the CLI's answer: exit 2, that message, no traceback."""
    from click.testing import CliRunner

    from thymio_bt.cli import main
    from thymio_bt.mission.loader import load_mission

    start = time.process_time()
    with _deadline(), pytest.raises(UserError) as caught:
        load_mission(path)
    spent = time.process_time() - start
    assert spent < BUDGET, f"{spent:.2f} s of CPU time"
    (problem,) = caught.value.problems
    assert problem.file == str(path) and problem.line > 0 and problem.hint
    with _deadline():
        result = CliRunner().invoke(main, ["validate", str(path)])
    assert result.exit_code == 2 and "Traceback" not in result.output and "RecursionError" not in result.output
    assert f"{path}:{problem.line}:" in result.output
    return problem


def test_three_thousand_chained_subtrees_stop_at_the_nesting_limit(tmp_path):
    trees = "".join(f'<BehaviorTree ID="T{i}"><SubTree ID="T{i + 1}"/></BehaviorTree>\n' for i in range(3000))
    path = _mission(
        tmp_path, '<SubTree ID="T0"/>', trees + '<BehaviorTree ID="T3000"><AlwaysSuccess/></BehaviorTree>\n'
    )
    problem = _refused(path)
    assert f"subtrees nest more than {MAX_SUBTREE_DEPTH} deep" in problem.message
    # the <SubTree> that went one level too deep: the one in T63 (line 4 + 63), naming T64
    assert problem.line == 4 + MAX_SUBTREE_DEPTH - 1 and "T64" in problem.message


def test_subtrees_used_twice_thirty_levels_deep_stop_at_the_node_limit(tmp_path):
    trees = "".join(
        f'<BehaviorTree ID="T{i}"><Sequence><SubTree ID="T{i + 1}"/><SubTree ID="T{i + 1}"/></Sequence>'
        "</BehaviorTree>\n"
        for i in range(30)
    )
    path = _mission(tmp_path, '<SubTree ID="T0"/>', trees + '<BehaviorTree ID="T30"><AlwaysSuccess/></BehaviorTree>\n')
    problem = _refused(path)  # 2**31 nodes once expanded
    assert f"expands to more than {MAX_NODES} nodes" in problem.message and "T0 -> T1" in problem.message
    assert problem.line >= 4 and problem.column > 1  # the <SubTree> being expanded when the limit passed


def test_a_long_script_copied_by_subtrees_stops_at_the_text_limit(tmp_path):
    script = "x := 1; " * 2000  # 16 kB, copied 256 times
    trees = "".join(
        f'<BehaviorTree ID="T{i}"><Sequence><SubTree ID="T{i + 1}"/><SubTree ID="T{i + 1}"/></Sequence>'
        "</BehaviorTree>\n"
        for i in range(8)
    )
    leaf = f'<BehaviorTree ID="T8"><Script code="{script}"/></BehaviorTree>\n'
    problem = _refused(_mission(tmp_path, '<SubTree ID="T0"/>', trees + leaf))
    assert f"more than {MAX_TEXT} characters" in problem.message


def test_subtrees_that_nest_the_tree_too_deep_stop_at_the_depth_limit(tmp_path):
    trees = "".join(
        f'<BehaviorTree ID="T{i}"><Sequence><Inverter><SubTree ID="T{i + 1}"/></Inverter></Sequence></BehaviorTree>\n'
        for i in range(50)
    )
    path = _mission(tmp_path, '<SubTree ID="T0"/>', trees + '<BehaviorTree ID="T50"><AlwaysSuccess/></BehaviorTree>\n')
    problem = _refused(path)
    assert f"nested deeper than {MAX_DEPTH} levels" in problem.message


@pytest.mark.parametrize("where", ["port", "setting", "literal port"])
def test_json_nested_five_thousand_deep_is_refused_where_it_is_written(where, tmp_path):
    deep = "[" * 5000 + "]" * 5000
    if where == "port":
        path = _mission(tmp_path, f'<FollowWaypoints waypoints="{deep}"/>')
    elif where == "setting":
        path = _mission(tmp_path, "<AlwaysSuccess/>", settings=f" plugins='{deep}'")
    else:
        trees = '<BehaviorTree ID="Go"><FollowWaypoints waypoints="{points}"/></BehaviorTree>\n'
        path = _mission(tmp_path, f'\n<SubTree ID="Go" points="{deep}"/>', trees)
    problem = _refused(path)
    assert f"nested deeper than {MAX_JSON_NESTING} levels" in problem.message
    assert problem.line == {"port": 3, "setting": 2, "literal port": 4}[where]


def test_json_as_deep_as_allowed_is_read(tmp_path):
    deep = "[" * MAX_JSON_NESTING + "]" * MAX_JSON_NESTING
    from thymio_bt.btcpp.xml_reader import read_xml_mission

    body = read_xml_mission(_mission(tmp_path, f'<FollowWaypoints waypoints="{deep}"/>'))["tree"]["FollowWaypoints"]
    assert isinstance(body["waypoints"], list)


def test_a_subtree_that_uses_itself_is_one_message(tmp_path):
    trees = (
        '<BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree>\n<BehaviorTree ID="B"><SubTree ID="A"/></BehaviorTree>\n'
    )
    problem = _refused(_mission(tmp_path, '<SubTree ID="A"/>', trees))
    assert "subtree 'A' uses itself (Main -> A -> B -> A)" in problem.message and problem.line == 5
