"""Contact is a collision on every backend: a report never says 0 collisions with 0 clearance (#36).

The rule lives in the runner, so a backend whose contact detection misses a touch (or that has
none, as a stand-in for one) is held to it: here the simulation with its contact callback cut off.
"""

import pytest

from thymio_bt.backends import backend_kind
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import CONTACT, Run

WAIT = """\
name: touching
maze: arena
start: centre
expect: {no_collision: true}
tree:
  sequence: [{Wait: {seconds: 1}}]
"""

PUSH = """\
name: pushing
maze: arena
start: centre
time_limit: 20
tree:
  MoveDistance: {distance: 0.8, speed: 0.15}
"""


def _mission(folder, text):
    (folder / "m.yaml").write_text(text)
    return load_mission(folder / "m.yaml")


def _blind(mission, gap_at=None):
    """The simulation of ``mission`` counting no collision; from ``gap_at`` s on it says clearance 0."""
    backend = backend_kind("sim").create(mission, mission.seed, {})
    quiet = lambda *args: None  # noqa: E731
    backend.space.on_collision(1, 2, begin=quiet, separate=quiet)  # robot and wall: no collision counted
    if gap_at is not None:
        advance = backend.advance

        def advance_and_touch(duration):
            advance(duration)
            if backend.time() >= gap_at:
                backend.min_clearance = 0.0

        backend.advance = advance_and_touch
    return backend


def test_a_backend_reporting_zero_clearance_and_no_collision_gets_one(tmp_path):
    mission = _mission(tmp_path, WAIT)
    result = Run(mission, backend=_blind(mission, gap_at=0.5)).run()
    report = result.report()
    assert (report["collisions"], report["min_clearance"]) == (1, 0.0)
    assert [e["t"] for e in report["events"] if e["kind"] == "collision"] == [0.5]
    assert report["status"] == "FAILURE" and report["expectations"]["failed"] == ["no_collision: 1 collision"]


def test_a_robot_pushing_a_wall_unseen_by_its_backend_fails_with_collision(tmp_path):
    mission = _mission(tmp_path, PUSH)
    backend = _blind(mission)
    result = Run(mission, backend=backend).run()
    assert result.min_clearance is not None and result.min_clearance <= CONTACT
    assert result.collisions == 1 and (result.status, result.code) == ("FAILURE", "COLLISION")


@pytest.mark.parametrize("gap, collisions", [(0.0, 1), (CONTACT, 1), (2 * CONTACT, 0)])
def test_contact_is_a_gap_at_or_below_a_micrometre(tmp_path, gap, collisions):
    mission = _mission(tmp_path, WAIT)
    backend = _blind(mission)
    backend.min_clearance = gap
    assert Run(mission, backend=backend).run().collisions == collisions


def test_the_summary_never_prints_a_gap_that_is_not_contact_as_zero(tmp_path):
    from thymio_bt.cli.app import clearance_text

    assert clearance_text(None) == "n/a"
    assert clearance_text(0.0154) == "0.0154 m"
    assert clearance_text(0.0) == "0.0000 m"
    assert clearance_text(3e-5) == "0.000030 m"
