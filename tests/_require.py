"""Tests that need an optional component (Aseba Playground, ROS 2, an extra's library) skip on a
developer's machine without it, and fail in CI, which sets ``THYMIO_BT_REQUIRE_ALL=1`` after
installing everything: a missing component must never pass CI as a skip."""

from __future__ import annotations

import importlib
import os
import shutil
from pathlib import Path
from types import ModuleType

import pytest

REQUIRE_ALL = os.environ.get("THYMIO_BT_REQUIRE_ALL") == "1"


def missing(what: str) -> None:
    """Skip (locally) or fail (in CI) because ``what`` is not installed."""
    if REQUIRE_ALL:
        pytest.fail(f"{what} is required in CI (THYMIO_BT_REQUIRE_ALL=1) but missing")
    pytest.skip(f"{what} is not installed", allow_module_level=True)


def module(name: str) -> ModuleType:
    """Import ``name`` or skip/fail as :func:`missing` does."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        missing(f"Python module {name}")
        raise AssertionError("unreachable") from exc


def program(name: str) -> str:
    """The path of program ``name`` on PATH, or skip/fail as :func:`missing` does."""
    path = shutil.which(name)
    if path is None:
        missing(f"program {name}")
    assert path is not None
    return path


def enki_fix() -> Path:
    """The library correcting the Playground's Enki (built now if need be), or skip/fail as
    :func:`missing` does (it needs g++ and libenki-dev)."""
    from thymio_bt.backends.playground.enki_fix import enki_fix as build

    library, why = build()
    if library is None:
        missing(f"the Playground's Enki correction ({why})")
    assert library is not None
    return library
