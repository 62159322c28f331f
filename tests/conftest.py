"""Our own suite clears py_trees' global blackboard around every test (the plugin does it only after
tests that made thymio-bt behaviours), starts each test in an empty working folder of its own, and
skips the tests marked ``slow`` (real time over ~20 s: the Playground missions) unless asked:
``--run-slow``, or ``THYMIO_BT_REQUIRE_ALL=1`` as CI sets, and runs the longest test files first
(CI runs two files side by side: ``pytest -n 2``).
Once the tests are over, a process that has not ended within :data:`EXIT_GRACE` s prints every
thread's stack and exits 1: something a test started is holding it (a Dask client waiting on its
loop once held CI's pytest after its last test until the job's time limit). A session started with
Ctrl-C ignored (a shell's background job: ``nohup ... &``) gets Python's handler back, so that the
tests of what Ctrl-C does, in this process and in the commands they start, test it."""

import faulthandler
import os
import shutil
import signal
import sys

import pytest

from thymio_bt.testing import clear_blackboard

pytest_plugins = ["pytester"]


@pytest.fixture(scope="session")
def browser(tmp_path_factory: pytest.TempPathFactory):
    """One headless Chromium for every test that reads a page in a real browser (tests/_chromium.py)."""
    from _chromium import BROWSERS, Chromium
    from _require import missing

    exe = next((path for name in BROWSERS if (path := shutil.which(name))), None)
    if exe is None:
        missing(f"a Chromium browser ({', '.join(BROWSERS)})")
    assert exe is not None
    chromium = Chromium(exe, tmp_path_factory.mktemp("chromium"))
    try:
        chromium.call("Browser.getVersion")
        yield chromium
    finally:
        chromium.close()


@pytest.fixture(autouse=True)
def _clean_blackboard():
    yield from clear_blackboard()


@pytest.fixture(autouse=True)
def _empty_working_folder(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each test starts in an empty folder of its own, so that a path written relative to the checkout
    (``missions/square.yaml``) fails wherever pytest starts, not only outside the repository: tests
    name files from their ``ROOT``, and a test that means the working folder sets it itself."""
    monkeypatch.chdir(tmp_path_factory.mktemp("cwd"))


def pytest_configure(config):
    """Ctrl-C as Python sets it up: a non-interactive shell starts background jobs with SIGINT
    ignored, and children inherit that (every SIGINT test failed under ``nohup .ci/run &``)."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_addoption(parser):
    """``--run-slow``: run the tests marked slow too."""
    parser.addoption("--run-slow", action="store_true", help="also run the tests marked slow (real time)")


#: the test files that take longest (docs/development.md: measured), longest first: they run first, so
#: that with ``-n 2`` (a file whole in one worker) none starts last and keeps a worker busy alone
LONGEST = (
    "test_playground_missions.py",
    "test_places.py",
    "test_hostile_surfaces.py",
    "test_ros2.py",
    "test_interrupts.py",
    "test_hostile_files.py",
    "test_packaging.py",
    "test_robotics_tools.py",
    "test_whatif_backends.py",
    "test_plugins_doc.py",
    "test_grade.py",
    "test_aseba_hostile.py",
    "test_calibrate.py",
    "test_ros2_verdicts.py",
)


def first_the_longest(name: str) -> int:
    """Where a test file goes in the run: :data:`LONGEST` in its order, then the rest as collected."""
    return LONGEST.index(name) if name in LONGEST else len(LONGEST)


def pytest_collection_modifyitems(config, items):
    """The longest files first (a stable sort: every xdist worker collects the same order); skip the
    tests marked slow, unless asked or in CI."""
    items.sort(key=lambda item: first_the_longest(item.path.name))
    if config.getoption("--run-slow") or os.environ.get("THYMIO_BT_REQUIRE_ALL") == "1":
        return
    skip = pytest.mark.skip(reason="slow (real time): pytest --run-slow runs it, as CI does")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


#: wall-clock seconds the process gets to end after the tests
EXIT_GRACE = 120


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """Arm the watchdog for the interpreter's shutdown (a daemon timer of faulthandler's: it does not
    itself keep the process alive)."""
    faulthandler.dump_traceback_later(EXIT_GRACE, exit=True, file=sys.__stderr__)
