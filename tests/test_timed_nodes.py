"""The timed nodes of both vocabularies (``timeout``, ``delay``; BT.CPP's ``Timeout``, ``Delay``,
``Sleep``) keep their time with one rule, :class:`SimTimer`: a span of simulated time that is over
at the same tick for all of them, even when the tick's time is a float sum a hair short of it."""

from __future__ import annotations

from types import SimpleNamespace

from py_trees.behaviours import Running, Success
from py_trees.common import Status

from thymio_bt.behaviours.flow.decorators import Delay
from thymio_bt.behaviours.flow.primitives import SimTimeout, SimTimer
from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.btcpp.runtime import decorators as bd
from thymio_bt.btcpp.runtime.scripted import Sleep

PERIOD = 0.1  # ten ticks of it add up to 0.9999999999999999 s, not 1 s


class Clock:
    """The run's simulated clock, advanced by float sums as the runner does."""

    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def _ticks_until(node: object, clock: Clock, done: object) -> int:
    """Tick ``node`` at each period until ``done(node)``; the tick count then."""
    for count in range(1, 100):
        tick(node)  # type: ignore[arg-type]
        if done(node):  # type: ignore[operator]
            return count
        clock.t += PERIOD
    raise AssertionError("never done")


def _nodes(clock: Clock) -> dict[str, object]:
    robot = SimpleNamespace(exists=lambda: False, time=clock)
    ctx = SimpleNamespace(robot=robot, now=clock, collision_count=lambda: 0)
    return {
        "timeout": SimTimeout("timeout", Running("run"), duration=1.0, clock=clock),
        "delay": Delay("delay", Success("go"), 1.0, clock),
        "bt_timeout": bd.Timeout("bt_timeout", Running("run"), 1000, clock),
        "bt_delay": bd.Delay("bt_delay", Success("go"), 1000, clock),
        "bt_sleep": Sleep("bt_sleep", Sleep.Params(msec=1000), ctx),
    }


def test_every_timed_node_keeps_its_time_with_one_sim_timer() -> None:
    """Each timed node's span is a SimTimer (no node with clock arithmetic of its own)."""
    clock = Clock()
    nodes = _nodes(clock)
    for node in nodes.values():
        tick(node)  # type: ignore[arg-type]
    assert {name: type(node.timer).__name__ for name, node in nodes.items()} == dict.fromkeys(nodes, "SimTimer")  # type: ignore[attr-defined]


def test_the_span_ends_at_the_same_tick_in_both_vocabularies() -> None:
    """One second of ticks of 0.1 s: every node sees it over at the 11th tick (t = 0.9999999999999999)."""
    clock = Clock()
    ended = {}
    for name, node in _nodes(clock).items():
        clock.t = 0.0
        ended[name] = _ticks_until(node, clock, lambda n: n.status is not Status.RUNNING)
        assert clock.t == sum([PERIOD] * 10) < 1.0
    assert ended == dict.fromkeys(ended, 11)


def test_a_timer_reads_its_span_from_its_start() -> None:
    clock = Clock()
    timer = SimTimer(0.5, clock)
    clock.t = 2.0
    timer.start()
    clock.t = 2.25
    assert (timer.over(), timer.left()) == (False, 0.25)
    clock.t = 2.5 - 1e-10
    assert timer.over()
    timer.forget()
    assert timer.end is None


def test_both_time_limits_keep_why_they_failed_until_they_start_again() -> None:
    clock = Clock()
    for name in ("timeout", "bt_timeout"):
        clock.t = 0.0
        node = _nodes(clock)[name]
        _ticks_until(node, clock, lambda n: n.status is not Status.RUNNING)
        assert node.status is Status.FAILURE and node.failure[0] == "TIMEOUT", name  # type: ignore[attr-defined]
        tick(node)  # type: ignore[arg-type]  # started again: RUNNING, the old time-out forgotten
        assert node.status is Status.RUNNING and node.failure is None, name  # type: ignore[attr-defined]
