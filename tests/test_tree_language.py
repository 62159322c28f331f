"""Each composite and decorator of the mission language, with its semantics, through real runs."""

import pytest

from thymio_bt.testing import run_tree, world

ARENA = world("arena")


def starts(result, name):
    return sum(1 for e in result.events if e["kind"] == "behaviour_start" and e["name"] == name)


def wait(seconds, name=None):
    return {"Wait": {"seconds": seconds, **({"name": name} if name else {})}}


def test_sequence_resumes_at_the_running_child_but_reactive_sequence_rechecks_conditions():
    # the robot drives towards the wall; WallAhead(3cm) only becomes true on the way
    moving = {"MoveDistance": {"distance": 0.6, "speed": "10cm/s"}}
    condition = {"invert": {"WallAhead": {"distance": "3cm"}}}
    plain = run_tree({"sequence": [condition, moving]}, ARENA, seconds=30)
    reactive = run_tree({"reactive_sequence": [condition, moving]}, ARENA, seconds=30)
    assert plain.status == "FAILURE" and plain.code == "COLLISION"  # never re-checked: hits the wall
    assert reactive.status == "FAILURE" and reactive.collisions == 0  # stopped 3 cm from the wall
    assert reactive.final_proximity["front_center"] < 0.03


def test_selector_tries_alternatives_in_order():
    tree = {"selector": [{"SideOpen": {"side": "left"}}, wait(1, "fallback")]}
    result = run_tree(tree, world("corridor"), seconds=5)
    assert result.status == "SUCCESS" and starts(result, "Wait") == 1


def test_reactive_selector_interrupts_a_lower_priority_child():
    # a higher-priority condition becomes true while the lower child runs: it takes over
    tree = {
        "reactive_selector": [
            {"WallAhead": {"distance": "5cm"}},
            {"MoveDistance": {"distance": 0.6, "speed": "10cm/s"}},
        ]
    }
    result = run_tree(tree, ARENA, seconds=30)
    assert result.status == "SUCCESS" and result.collisions == 0
    assert 0.045 < result.final_proximity["front_center"] <= 0.05
    ends = [e for e in result.events if e["kind"] == "behaviour_end" and e["name"] == "MoveDistance"]
    assert ends[0]["status"] == "INVALID"  # interrupted, and stopped


def test_parallel_policies():
    all_ = run_tree({"parallel": {"policy": "success_on_all", "children": [wait(1), wait(2)]}}, ARENA, seconds=10)
    one = run_tree({"parallel": {"policy": "success_on_one", "children": [wait(1), wait(2)]}}, ARENA, seconds=10)
    assert all_.sim_time == pytest.approx(2.0, abs=0.11) and one.sim_time == pytest.approx(1.0, abs=0.11)


def test_repeat_times_forever_and_until():
    times = run_tree({"repeat": {"times": 3, "do": wait(0.5)}}, ARENA, seconds=10)
    assert times.status == "SUCCESS" and starts(times, "Wait") == 3
    forever = run_tree({"repeat": {"times": "forever", "do": wait(0.5)}}, ARENA, seconds=3)
    assert forever.status == "TIMEOUT" and starts(forever, "Wait") >= 5
    until = run_tree(
        {"repeat": {"until": {"WallAhead": {}}, "do": {"MoveDistance": {"distance": 0.1}}}}, ARENA, seconds=60
    )
    assert until.status == "SUCCESS" and until.final_proximity["front_center"] is not None


def test_retry_gives_a_failing_child_more_attempts_then_fails():
    result = run_tree({"retry": {"times": 3, "do": {"WallAhead": {}}}}, ARENA, seconds=5)
    assert result.status == "FAILURE" and result.ticks == 3


def test_timeout_uses_simulated_seconds():
    result = run_tree({"timeout": {"seconds": "1.5 s", "do": wait(10)}}, ARENA, seconds=20)
    assert result.status == "FAILURE" and result.code == "TIMEOUT"
    assert result.sim_time == pytest.approx(1.5, abs=0.11)


def test_invert_force_success_force_failure():
    assert run_tree({"invert": {"WallAhead": {}}}, ARENA, seconds=1).status == "SUCCESS"
    assert run_tree({"force_success": {"WallAhead": {}}}, ARENA, seconds=1).status == "SUCCESS"
    assert run_tree({"force_failure": wait(0.2)}, ARENA, seconds=2).status == "FAILURE"


def test_until_reruns_its_child_until_the_status():
    result = run_tree(
        {"until": {"status": "success", "do": {"sequence": [{"MoveDistance": {"distance": 0.1}}, {"WallAhead": {}}]}}},
        ARENA,
        seconds=60,
    )
    assert result.status == "SUCCESS" and starts(result, "MoveDistance") >= 3


def test_guard_stops_its_child_when_the_condition_turns_false():
    tree = {
        "guard": {
            "condition": {"invert": {"WallAhead": {"distance": "4cm"}}},
            "do": {"MoveDistance": {"distance": 0.6}},
        }
    }
    result = run_tree(tree, ARENA, seconds=30)
    assert result.status == "FAILURE" and result.collisions == 0
    assert 0.03 < result.final_proximity["front_center"] <= 0.04


def test_one_shot_runs_its_child_once():
    tree = {"repeat": {"times": 3, "do": {"sequence": [{"one_shot": wait(1)}, wait(0.2, "each")]}}}
    result = run_tree(tree, ARENA, seconds=10)
    assert result.status == "SUCCESS"
    assert [e["path"].split("/")[-1] for e in result.events if e["kind"] == "behaviour_start"].count("Wait") == 1


def test_subtrees_with_parameters_and_defaults():
    subtrees = {"hop": {"parameters": {"d": "5cm"}, "tree": {"MoveDistance": {"distance": "$d"}}}}
    tree = {"sequence": [{"hop": {}}, {"hop": {"d": "10cm"}}]}
    result = run_tree(tree, ARENA, start=[0.3, 0.6, 0], seconds=20, subtrees=subtrees)
    moved = [e["distance"] for e in result.events if e["kind"] == "behaviour_end"]
    assert moved == pytest.approx([0.05, 0.10], abs=0.001)


def test_parameters_and_expressions():
    result = run_tree(
        {"MoveDistance": {"distance": "2*$side - 10cm"}},
        ARENA,
        start=[0.3, 0.6, 0],
        seconds=20,
        parameters={"side": "15cm"},
    )
    assert result.final_pose.x == pytest.approx(0.5, abs=0.001)


def test_delay_waits_in_simulated_time_then_runs_the_child():
    result = run_tree({"delay": {"seconds": 2, "do": wait(1)}}, ARENA, seconds=10)
    assert result.status == "SUCCESS" and result.sim_time == pytest.approx(3.0, abs=0.11)
    started = [e["t"] for e in result.events if e["kind"] == "behaviour_start" and e["name"] == "Wait"]
    assert started == [pytest.approx(2.0, abs=0.11)]  # the child starts after the delay
    failing = run_tree({"delay": {"seconds": "500ms", "do": {"invert": wait(0.2)}}}, ARENA, seconds=10)
    assert failing.status == "FAILURE"  # the child's result is passed on
