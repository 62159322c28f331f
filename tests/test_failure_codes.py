"""Failure codes are a FailureCode from the node or the runner that sets one to the report (issue
45): the enum inside the package, its text only where JSON is written, byte for byte as before."""

from __future__ import annotations

import json

from thymio_bt.behaviours import FailureCode
from thymio_bt.errors import StopRun
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.testing import run_tree, world


def test_the_runner_ends_a_run_with_a_failure_code_member():
    timed_out = Run(load_mission("maze_part1_2", {"time_limit": "5"})).run()
    assert timed_out.code is FailureCode.TIMEOUT

    def stop(run: Run) -> None:
        raise StopRun("enough")

    stopped = Run(load_mission("square")).run(on_tick=stop)
    assert stopped.code is FailureCode.STOPPED and stopped.reason == "enough"


def test_a_behaviour_failure_keeps_its_member_to_the_result_and_its_event():
    result = run_tree({"sequence": [{"MoveDistance": {"distance": "2m"}}, "Stop"]}, world("corridor"))
    assert result.code is FailureCode.COLLISION
    assert [e["code"] for e in result.events if "code" in e] == [FailureCode.COLLISION]


def test_a_code_reads_and_is_written_as_its_text():
    code = FailureCode.ROBOT_LOST
    assert code == "ROBOT_LOST" and str(code) == "ROBOT_LOST" and f"[{code}]" == "[ROBOT_LOST]"
    assert json.dumps({"code": code}) == '{"code": "ROBOT_LOST"}'
    result = Run(load_mission("maze_part1_2", {"time_limit": "5"})).run()
    assert json.dumps(result.report()["code"]) == '"TIMEOUT"'


def test_both_time_limits_say_why_their_child_failed_and_a_new_start_forgets_it():
    slow = {"MoveDistance": {"distance": 0.3, "speed": "1cm/s", "name": "crawl"}}
    yaml_limit = run_tree({"timeout": {"seconds": 2, "do": slow}}, world("arena"), seconds=10)
    btcpp_limit = run_tree({"bt_timeout": {"msec": 2000, "do": slow}}, world("arena"), seconds=10)
    assert (yaml_limit.code, yaml_limit.reason) == (FailureCode.TIMEOUT, "'crawl' did not finish within 2 s")
    assert (btcpp_limit.code, btcpp_limit.reason) == (FailureCode.TIMEOUT, "'crawl' did not finish within 2000 ms")
