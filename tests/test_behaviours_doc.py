"""docs/behaviours_reference.md is what the node registry says today: regenerate it with
``python docs/make_behaviours.py`` when a node, its docstring or its parameters change."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_behaviour_reference_is_up_to_date():
    spec = importlib.util.spec_from_file_location("make_behaviours", ROOT / "docs" / "make_behaviours.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    page = (ROOT / "docs" / "behaviours_reference.md").read_text(encoding="utf-8")
    assert page == module.reference(), "docs/behaviours_reference.md is stale: run python docs/make_behaviours.py"
    for name in ("MoveUntilWall", "WallFollow", "sequence", "repeat"):
        assert f"\n## {name}\n" in page


def test_the_architecture_s_steps_to_add_a_node_regenerate_the_reference():
    """docs/architecture.md's "add a behaviour" and "add a decorator" left out the step the test above
    enforces; and its data flow named py_trees' ``tree.tick()``, which the runner avoids."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    steps = text.split("## What one touches to add")[1]
    behaviour, decorator = (
        steps.split("- **a decorator")[0],
        steps.split("- **a decorator")[1].split("- **a backend")[0],
    )
    assert "python docs/make_behaviours.py" in behaviour and "reference page" in decorator
    flow = text.split("## Data flow")[1].split("## What one touches")[0]
    runner = (ROOT / "thymio_bt" / "run" / "runner.py").read_text(encoding="utf-8")
    assert "tree.tick()" not in flow.split("```")[1] and "tick(root)" in flow and "tick(self.root)" in runner
