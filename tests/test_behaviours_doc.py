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
