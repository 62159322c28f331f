"""The pytest plugin (registered through the ``pytest11`` entry point when thymio-bt is installed).

It clears py_trees' process-global blackboard around every test and offers the ``thymio``
fixture with the helpers of :mod:`thymio_bt.testing`.

Example::

    def test_stop(thymio):
        result = thymio.run_tree({"MoveUntilWall": {"distance": "5cm"}}, thymio.world("corridor"))
        assert result.status == "SUCCESS"
"""

from types import SimpleNamespace
from typing import Iterator

import pytest

from .testing import clear_blackboard, run_mission_file, run_tree, world


@pytest.fixture(autouse=True)
def _thymio_bt_clean_blackboard() -> Iterator[None]:
    yield from clear_blackboard()


@pytest.fixture
def thymio() -> SimpleNamespace:
    """The testing helpers: ``run_tree``, ``world``, ``run_mission_file``."""
    return SimpleNamespace(run_tree=run_tree, world=world, run_mission_file=run_mission_file)
