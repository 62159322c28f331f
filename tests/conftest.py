"""Our own suite clears py_trees' global blackboard around every test (the plugin does it only after
tests that made thymio-bt behaviours), and skips the tests marked ``slow`` (real time over ~20 s:
the Playground missions) unless asked: ``--run-slow``, or ``THYMIO_BT_REQUIRE_ALL=1`` as CI sets."""

import os

import pytest

from thymio_bt.testing import clear_blackboard

pytest_plugins = ["pytester"]


@pytest.fixture(autouse=True)
def _clean_blackboard():
    yield from clear_blackboard()


def pytest_addoption(parser):
    """``--run-slow``: run the tests marked slow too."""
    parser.addoption("--run-slow", action="store_true", help="also run the tests marked slow (real time)")


def pytest_collection_modifyitems(config, items):
    """Skip the tests marked slow, unless asked or in CI."""
    if config.getoption("--run-slow") or os.environ.get("THYMIO_BT_REQUIRE_ALL") == "1":
        return
    skip = pytest.mark.skip(reason="slow (real time): pytest --run-slow runs it, as CI does")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
