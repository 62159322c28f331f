"""Every docstring example of the package runs (the ``>>>`` lines), as pymunk runs its own.

A module whose optional library is missing skips here (fails in CI, through ``_require``); every
other module must import and pass. Examples that need a file use the shipped missions and mazes by
name where they can; the grader's examples name files as a teacher in the checkout types them
(``missions/maze_part1_2.yaml``, ``examples/class/ada``), so the examples run with the checkout as
their working folder, wherever pytest started.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil
from pathlib import Path

import pytest
from _require import missing

import thymio_bt

ROOT = Path(__file__).resolve().parents[1]
MODULES = sorted(
    m.name
    for m in pkgutil.walk_packages(thymio_bt.__path__, "thymio_bt.")
    if not m.name.endswith("__main__") and ".data" not in m.name
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    try:
        module = importlib.import_module(name)
    except ImportError as exc:
        missing(f"{exc.name or exc} (for {name})")
        return
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in finder.find(module, name, module=module):
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name} (output above)"


def test_the_examples_cover_the_package() -> None:
    """Most modules show how they are used: at least half have a run example."""
    with_examples = 0
    for name in MODULES:
        try:
            module = importlib.import_module(name)
        except ImportError:
            continue
        if any(t.examples for t in doctest.DocTestFinder().find(module, name, module=module)):
            with_examples += 1
    assert with_examples >= len(MODULES) // 2, f"{with_examples} of {len(MODULES)} modules have examples"
