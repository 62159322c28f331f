"""The runner's direct tick (thymio_bt.behaviours.flow.ticking) against py_trees' generator tick: every
mission, with noise, ends in the same report both ways; and each node kind alone behaves alike."""

from pathlib import Path

import py_trees
import pytest
from py_trees.common import ParallelPolicy, Status

from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.mission import load_mission
from thymio_bt.run import runner
from thymio_bt.run.runner import Run

MISSIONS = sorted((Path(__file__).resolve().parent.parent / "missions").glob("*.yaml"))


def _report(mission, seed: int) -> dict:
    report = Run(mission, seed=seed).run().report()
    del report["wall_time"], report["real_time_factor"]
    return report


def _tick_once(root: py_trees.behaviour.Behaviour) -> None:
    """py_trees' own tick of the whole tree, through every node's generator."""
    root.tick_once()


class _ByGenerators(dict):
    """A stand-in for the runner's table of direct ticks: every root ticked by :func:`_tick_once`."""

    def __missing__(self, kind: type) -> object:
        return _tick_once


@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.stem)
def test_every_mission_ends_the_same_either_way(path, monkeypatch):
    mission = load_mission(path, {"noise.wheel": "0.03", "noise.range_sd": "0.002", "noise.odometry": "0.01"})
    direct = _report(mission, 5)
    monkeypatch.setattr(runner, "TICK_OF", _ByGenerators())
    assert _report(mission, 5) == direct


class Scripted(py_trees.behaviour.Behaviour):
    """A leaf returning a scripted status per tick and recording its hooks."""

    def __init__(self, name, script, log):
        super().__init__(name)
        self.script, self.log, self.i = list(script), log, 0

    def initialise(self):
        self.log.append(f"{self.name}.initialise")

    def update(self):
        status = self.script[min(self.i, len(self.script) - 1)]
        self.i += 1
        return status

    def terminate(self, new_status):
        self.log.append(f"{self.name}.terminate({new_status.name})")


R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE


def _trees(log):
    """Small trees of every kind the direct tick handles, with leaves that change their minds."""

    def leaves(prefix, *scripts):
        return [Scripted(f"{prefix}{i}", s, log) for i, s in enumerate(scripts)]

    return [
        py_trees.composites.Sequence("seq", memory=True, children=leaves("a", [R, S], [S], [R, F])),
        py_trees.composites.Sequence("rseq", memory=False, children=leaves("b", [S, S, F], [R, R, S], [S])),
        py_trees.composites.Selector("sel", memory=True, children=leaves("c", [F], [R, F], [R, S])),
        py_trees.composites.Selector("rsel", memory=False, children=leaves("d", [F, F, S], [R, S, R], [S])),
        py_trees.composites.Parallel(
            "all", policy=ParallelPolicy.SuccessOnAll(synchronise=True), children=leaves("e", [R, S], [R, R, S], [S])
        ),
        py_trees.composites.Parallel(
            "one", policy=ParallelPolicy.SuccessOnOne(), children=leaves("f", [R, R, R, S], [R, F])
        ),
        py_trees.decorators.Inverter("inv", child=Scripted("g", [R, S], log)),
        py_trees.decorators.FailureIsSuccess("fis", child=Scripted("h", [R, F], log)),
    ]


def test_each_node_kind_ticks_alike():
    for index in range(len(_trees([]))):
        by_generator, direct = [], []
        a, b = _trees(by_generator)[index], _trees(direct)[index]
        for _ in range(5):
            a.tick_once()
            tick(b)
            assert [n.status for n in a.iterate()] == [n.status for n in b.iterate()], a.name
            assert getattr(a, "current_child", None) is None or a.current_child.name == b.current_child.name
        assert by_generator == direct, a.name
