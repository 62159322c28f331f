"""docs/plugins.md's plugin examples (the README's among them) are true: their Python type-checks with mypy (a
plugin that uses proximity() or pose() without checking for None does not) and runs, and the
subtree mission runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = (ROOT / "docs" / "plugins.md").read_text(encoding="utf-8")


def _blocks(text: str, language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", text, re.S)


def _files(tmp_path: Path) -> dict[str, Path]:
    """The Python blocks as the files they say they are (``# name.py`` first line)."""
    files = {}
    for block in _blocks(DOC, "python"):
        name = block.splitlines()[0].removeprefix("# ").strip()
        assert name.endswith(".py"), f"a block of docs/plugins.md does not name its file: {block[:60]!r}"
        files[name] = tmp_path / name
        files[name].write_text(block)
    return files


def test_the_plugin_examples_type_check_with_mypy(tmp_path: Path) -> None:
    """With the project's own mypy settings, as a student's CI would run it on their plugin."""
    from mypy import api

    files = {**_files(tmp_path), "spin_until_clear.py": ROOT / "examples" / "spin_until_clear.py"}
    assert {"back_off.py", "test_back_off.py", "spin_until_clear_short.py"} <= set(files)
    out, err, status = api.run(
        [
            "--config-file",
            str(ROOT / "pyproject.toml"),
            "--cache-dir",
            str(ROOT / ".mypy_cache"),
            *map(str, files.values()),
        ]
    )
    assert status == 0, out + err


def test_the_plugin_and_its_tests_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    files = _files(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    namespace: dict = {"__file__": str(files["test_back_off.py"])}
    exec(compile(files["test_back_off.py"].read_text(), str(files["test_back_off.py"]), "exec"), namespace)
    tests = [f for name, f in namespace.items() if name.startswith("test_") and callable(f)]
    assert len(tests) == 2
    for test in tests:
        test()


def test_the_subtree_example_runs() -> None:
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    (block,) = [b for b in _blocks(DOC, "yaml") if "subtrees:" in b]
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "two_squares.yaml"
        path.write_text(block)
        mission = load_mission(path)
    result = Run(mission).run()
    assert result.status == "SUCCESS", result.reason
    ends = [e for e in result.events if e["kind"] == "behaviour_end" and e["name"] == "MoveDistance"]
    assert len(ends) == 8
