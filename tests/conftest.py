"""Our own suite clears py_trees' global blackboard around every test (the plugin does it only after
tests that made thymio-bt behaviours)."""

import pytest

from thymio_bt.testing import clear_blackboard

pytest_plugins = ["pytester"]


@pytest.fixture(autouse=True)
def _clean_blackboard():
    yield from clear_blackboard()
