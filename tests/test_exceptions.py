"""One exception root: every exception thymio-bt defines derives from ThymioBtError (issue 45),
keeping its standard base, so ``except ThymioBtError`` catches them all and ``except ValueError``
still catches a ``UnitError``."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import warnings

import pytest

import thymio_bt
from thymio_bt.errors import ThymioBtError

#: signals that end a command: KeyboardInterrupts (and the grader's limit, a BaseException), so that
#: a student's or a library's ``except Exception`` cannot swallow them; deliberately outside the root
SIGNALS = {"Interrupted", "PlaygroundInterrupted", "RunLimit"}


def package_exceptions() -> list[type[BaseException]]:
    """Every exception class a module of the package defines (``__main__`` runs the CLI: skipped)."""
    found = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # _moved's old names
        for info in pkgutil.walk_packages(thymio_bt.__path__, "thymio_bt."):
            if info.name.endswith("__main__"):
                continue
            module = importlib.import_module(info.name)
            found += [
                c
                for c in vars(module).values()
                if inspect.isclass(c) and issubclass(c, BaseException) and c.__module__ == module.__name__
            ]
    return found


def test_every_exception_of_the_package_derives_from_the_root():
    classes = package_exceptions()
    assert len(classes) >= 12  # the walk found the package's exceptions, not nothing
    outside = sorted(c.__qualname__ for c in classes if not issubclass(c, ThymioBtError))
    assert set(outside) == SIGNALS, "derive a new exception from thymio_bt.errors.ThymioBtError"
    for c in classes:
        if c.__qualname__ in SIGNALS:
            assert not issubclass(c, Exception)  # were it an Exception, `except Exception` would eat it


@pytest.mark.parametrize(
    ("module", "name", "base"),
    [
        ("thymio_bt.inputs.units", "UnitError", ValueError),
        ("thymio_bt.btcpp.runtime.values", "ScriptError", ValueError),
        ("thymio_bt.backends.real.frames", "LinkError", ConnectionError),
        ("thymio_bt.run.sweep", "WorkerDied", RuntimeError),
        ("thymio_bt.btcpp.runtime.nodes", "NeverYields", RuntimeError),
    ],
)
def test_exceptions_keep_their_standard_base(module, name, base):
    cls = getattr(importlib.import_module(module), name)
    assert issubclass(cls, base) and issubclass(cls, ThymioBtError)


def test_the_root_catches_a_user_error_and_a_unit_error():
    from thymio_bt.inputs.units import parse_value
    from thymio_bt.mission import load_mission

    with pytest.raises(ThymioBtError):
        load_mission("no/such/mission.yaml")
    with pytest.raises(ValueError) as caught:
        parse_value("ten bananas")
    assert isinstance(caught.value, ThymioBtError)
