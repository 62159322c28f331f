"""Old module names (before the 0.2 layout) still import: the new module itself, with a warning.

Each test forgets the old names first (``monkeypatch`` puts ``sys.modules`` back afterwards), so the
finder of :mod:`thymio_bt._moved` answers whatever other tests imported before.
"""

from __future__ import annotations

import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import thymio_bt
from thymio_bt._moved import MOVED, SPLIT, new_name


def _forget_old_names(monkeypatch: pytest.MonkeyPatch) -> None:
    """Remove every old name (and its submodules) from ``sys.modules``, for this test only."""
    for name in list(sys.modules):
        if new_name(name) is not None or name in SPLIT:
            monkeypatch.delitem(sys.modules, name)


@pytest.mark.parametrize("old, new", sorted(MOVED.items()))
def test_an_old_name_imports_the_new_module_with_a_warning(old: str, new: str, monkeypatch: pytest.MonkeyPatch):
    target = importlib.import_module(new)
    _forget_old_names(monkeypatch)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        module = importlib.import_module(old)
    assert module is target
    assert sys.modules[old] is target
    assert module.__name__ == new and module.__spec__ is not None and module.__spec__.name == new
    deprecations = [w for w in caught if issubclass(w.category, DeprecationWarning)]
    assert [str(w.message) for w in deprecations] == [f"{old} moved to {new}: import it from there"]


def test_a_class_from_an_old_name_is_the_same_class(monkeypatch: pytest.MonkeyPatch):
    from thymio_bt.run.runner import Run

    _forget_old_names(monkeypatch)
    with pytest.warns(DeprecationWarning, match="thymio_bt.runner moved to thymio_bt.run.runner"):
        from thymio_bt.runner import Run as OldRun  # type: ignore[import-not-found]
    assert OldRun is Run


def test_a_submodule_of_a_moved_package_is_the_new_one_not_a_second_copy(monkeypatch: pytest.MonkeyPatch):
    world = importlib.import_module("thymio_bt.backends.sim.world")
    world.__dict__["_loaded_once"] = True  # a second execution of the file would not have it
    _forget_old_names(monkeypatch)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        old = importlib.import_module("thymio_bt.sim.world")
    assert [str(w.message) for w in caught] == [  # the package, then its submodule
        "thymio_bt.sim moved to thymio_bt.backends.sim: import it from there",
        "thymio_bt.sim.world moved to thymio_bt.backends.sim.world: import it from there",
    ]
    assert old is world and old.__dict__.get("_loaded_once") is True
    assert sys.modules["thymio_bt.sim"] is sys.modules["thymio_bt.backends.sim"]
    copies = [m for m in list(sys.modules.values()) if getattr(m, "__file__", None) == world.__file__]
    assert set(map(id, copies)) == {id(world)}


def test_in_a_fresh_process_the_old_submodule_loads_its_file_once():
    """Nothing imported before: the old package's import warns first, and the file is one module."""
    code = (
        "import sys, warnings\n"
        "warnings.simplefilter('error', DeprecationWarning)\n"
        "try:\n    import thymio_bt.sim.world\nexcept DeprecationWarning as w:\n    print(w)\n"
        "warnings.simplefilter('ignore', DeprecationWarning)\n"
        "import thymio_bt.sim.world as old, thymio_bt.backends.sim.world as new\n"
        "files = [n for n, m in sys.modules.items() if getattr(m, '__file__', None) == new.__file__]\n"
        "print(old is new, sorted(files))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.splitlines()
    assert out[0] == "thymio_bt.sim moved to thymio_bt.backends.sim: import it from there"
    assert out[-1] == "True ['thymio_bt.backends.sim.world', 'thymio_bt.sim.world']"


def test_names_that_did_not_move_are_left_to_the_other_finders():
    assert new_name("thymio_bt.mission") is None
    assert new_name("thymio_bt") is None
    assert new_name("json") is None
    assert new_name("thymio_bt.simulation") is None  # a prefix of a moved name is not the name
    assert new_name("thymio_bt.sim.world.inner") == "thymio_bt.backends.sim.world.inner"


@pytest.mark.parametrize("old", sorted(SPLIT))
def test_an_old_module_split_in_two_imports_the_names_of_both(old: str, monkeypatch: pytest.MonkeyPatch):
    """``mission.expect`` held what a mission expects (now ``plan.expect``) and the verdict on a run
    (now ``run.verdict``): both still import from the old name, the same objects, with one warning."""
    from thymio_bt.plan.expect import GoalRegion
    from thymio_bt.run.verdict import check

    _forget_old_names(monkeypatch)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        module = importlib.import_module(old)
    assert module.GoalRegion is GoalRegion and module.check is check
    assert module.__all__ == [name for new in SPLIT[old] for name in importlib.import_module(new).__all__]
    assert [str(w.message) for w in caught] == [
        f"{old} moved to thymio_bt.plan.expect and thymio_bt.run.verdict: import it from there"
    ]


@pytest.mark.parametrize("old", sorted({*MOVED, *SPLIT}))
def test_no_old_name_is_a_module_of_the_package_again(old: str):
    """The finder comes first on sys.meta_path: an old name that is a module again (``thymio_bt.btcpp``,
    an alias of the 0.1 layout, is the BT.CPP package now) would hide that module behind the alias."""
    path = Path(thymio_bt.__file__).parent.joinpath(*old.split(".")[1:])
    assert not path.with_suffix(".py").exists() and not (path / "__init__.py").exists(), old


def test_the_exception_root_is_public_api():
    """CHANGELOG.md and docs/architecture.md document ``ThymioBtError`` and ``StopRun`` as the
    exceptions to catch: ``from thymio_bt.errors import *`` and the API reference need them declared."""
    import thymio_bt.errors as errors

    assert {"ThymioBtError", "StopRun", "UserError", "Problem"} <= set(errors.__all__)
    assert all(issubclass(getattr(errors, name), errors.ThymioBtError) for name in ("StopRun", "UserError"))
