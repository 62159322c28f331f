"""The pytest plugin (registered through the ``pytest11`` entry point when thymio-bt is installed).

It offers the ``thymio`` fixture with the helpers of :mod:`thymio_bt.testing`, and clears py_trees'
process-global blackboard around the tests that ran thymio-bt trees, so one test's keys never leak
into the next. It is loaded by every pytest run of every project in the environment, so it imports
nothing heavy until a test asks for thymio-bt (loading it costs about a millisecond), and it leaves
alone the blackboard of tests that never made a thymio-bt behaviour.

Example (a test in a student's project; pytest passes it the fixture's value, as here):

>>> def test_stop(thymio):
...     result = thymio.run_tree({"MoveUntilWall": {"distance": "5cm"}}, thymio.world("corridor"))
...     assert result.status == "SUCCESS"
>>> test_stop(thymio.__wrapped__())
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from types import SimpleNamespace

import pytest


def _behaviours_so_far() -> int:
    """How many thymio-bt behaviours this process has made (0 while thymio-bt is not loaded)."""
    base = sys.modules.get("thymio_bt.behaviours.base")
    return base.RobotBehaviour.created if base is not None else 0


@pytest.fixture(autouse=True)
def _thymio_bt_clean_blackboard() -> Iterator[None]:
    before = _behaviours_so_far()
    yield
    if _behaviours_so_far() != before:  # this test made thymio-bt behaviours: remove what they left
        import py_trees

        py_trees.blackboard.Blackboard.clear()


@pytest.fixture
def thymio() -> SimpleNamespace:
    """The testing helpers: ``run_tree``, ``world``, ``run_mission_file``."""
    from thymio_bt.testing import run_mission_file, run_tree, world

    return SimpleNamespace(run_tree=run_tree, world=world, run_mission_file=run_mission_file)
