"""The example tests of docs/testing.md (they were the README's) are real: each ```python block
that defines test functions is run, as a test file in the repository root would run it (beside
``examples/``, which their plugin paths name). The README's two commands are the ones CI runs."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "testing.md"
BLOCKS = [b for b in re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S) if "def test_" in b]


def test_the_testing_doc_has_example_tests():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("block", BLOCKS, ids=lambda b: re.search(r"def (test_\w+)", b).group(1))
def test_testing_doc_example(block, monkeypatch):
    monkeypatch.chdir(ROOT)  # the examples name missions/... from the repository root
    namespace: dict = {}
    exec(compile(block, str(ROOT / "test_from_docs.py"), "exec"), namespace)
    tests = [f for name, f in namespace.items() if name.startswith("test_") and callable(f)]
    assert tests
    for test in tests:
        test()


def test_the_readme_test_command_is_the_one_ci_runs():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    install = 'python3 -m venv .venv && .venv/bin/pip install -e ".[dev]"'
    assert f"{install} && .venv/bin/python -m pytest -n 2\n" in readme
    assert f"\n{install}\n" in ci and "\n.venv/bin/python -m pytest -n 2\n" in ci
    run = "python3 -m venv .venv && .venv/bin/pip install . && .venv/bin/thymio-bt run missions/maze_part1_2.yaml"
    assert f"\n{run}\n" in readme


def test_the_readme_mission_runs(tmp_path):
    """The one mission the README shows succeeds, saved where it says (its maze is found by name)."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    (block,) = re.findall(r"```yaml\n(.*?)```", readme, re.S)
    assert "Saved as `missions/my_mission.yaml`" in readme
    path = tmp_path / "missions" / "my_mission.yaml"
    path.parent.mkdir()
    path.write_text(block)
    result = Run(load_mission(path)).run()
    assert result.status == "SUCCESS", result.reason
    assert [e["name"] for e in result.events if e["kind"] == "behaviour_end"] == [
        "MoveUntilWall",
        "TurnAngle",
        "MoveDistance",
    ]
