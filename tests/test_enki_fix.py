"""The correction of Enki 1.6.99's stale sensor rays (thymio_bt.backends.playground.enki_fix): it
builds once, defines the fixed IRSensor::init, is refused cleanly without what it needs, and the
Playground the backend starts has it loaded."""

import subprocess
from pathlib import Path

import _require
import pytest

from thymio_bt.backends.playground import enki_fix as fix
from thymio_bt.backends.playground.process import Playground
from thymio_bt.backends.playground.world import playground_world
from thymio_bt.maze import load_maze, resolve_maze
from thymio_bt.robot.interface import Pose


def test_it_builds_once_into_the_cache_and_defines_the_fixed_init(tmp_path, monkeypatch):
    _require.program("g++")
    _require.program("nm")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    library, why = fix.enki_fix()
    if library is None:
        _require.missing(f"the Playground's Enki correction ({why})")
    assert library.parent == tmp_path / "thymio-bt" and why == ""
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True, text=True).stdout
    assert " T _ZN4Enki8IRSensor4initEdPNS_5WorldE" in symbols  # Enki::IRSensor::init(double, World*)
    built = library.stat().st_mtime_ns
    assert fix.enki_fix() == (library, "") and library.stat().st_mtime_ns == built  # not built again
    assert [p.name for p in library.parent.iterdir()] == [library.name]  # no partial file left


def test_without_the_headers_it_says_why(tmp_path, monkeypatch):
    monkeypatch.setattr(fix, "HEADER", tmp_path / "IRSensor.h")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    library, why = fix.enki_fix()
    assert library is None and why.startswith("cannot correct it without") and not (tmp_path / "thymio-bt").exists()


def test_a_failed_build_is_a_reason_not_a_traceback(tmp_path, monkeypatch):
    _require.program("g++")
    broken = tmp_path / "broken.cpp"
    broken.write_text("this is not C++\n")
    header = tmp_path / "IRSensor.h"
    header.write_text("")
    monkeypatch.setattr(fix, "SOURCE", broken)
    monkeypatch.setattr(fix, "HEADER", header)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    library, why = fix.enki_fix()
    assert library is None and why.startswith("cannot correct it: g++ failed")
    assert list((tmp_path / "cache" / "thymio-bt").iterdir()) == []


def test_the_playground_runs_with_the_correction_loaded():
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    library = _require.enki_fix()
    world = playground_world(load_maze(resolve_maze("arena")), Pose(0.5, 0.5, 0.0), port=0)
    with Playground.start(world.text, preload=library) as pg:
        maps = [Path(f"/proc/{p.pid}/maps") for p in pg.processes]
        loaded = [m.read_text() for m in maps if m.exists()]
    assert any(str(library) in text for text in loaded), "no Playground process has the library mapped"


@pytest.fixture(autouse=True)
def _fresh_warning(monkeypatch):
    from thymio_bt.backends.playground import backend

    monkeypatch.setattr(backend, "_WARNED", [])


def test_the_backend_warns_once_when_it_cannot_correct(monkeypatch, capsys):
    from thymio_bt.backends.playground import backend

    monkeypatch.setattr(backend, "enki_fix", lambda: (None, "cannot correct it without g++"))
    assert backend._enki_fix() is None and backend._enki_fix() is None
    said = capsys.readouterr().err
    assert said.count("warning:") == 1 and "enki-community/enki#68" in said and "libenki-dev" in said
