"""Shared fixtures: py_trees' blackboard is process-global, so clear it around every test."""

import pytest

from thymio_bt.testing import clear_blackboard


@pytest.fixture(autouse=True)
def _clean_blackboard():
    yield from clear_blackboard()
