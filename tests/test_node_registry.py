"""One registry for every node: behaviours, composites and decorators are registered, validated,
documented and described in the schema from the same class; a plugin adds a decorator in one class."""

import textwrap

import py_trees
import pytest
from click.testing import CliRunner

from thymio_bt.analysis.schema import mission_schema
from thymio_bt.behaviours import ControlNode
from thymio_bt.behaviours.flow.composites import COMPOSITES
from thymio_bt.behaviours.flow.decorators import DECORATORS
from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.mission import default_registry, load_mission
from thymio_bt.run.runner import Run


def test_every_composite_and_decorator_is_in_the_registry():
    registry = default_registry()
    for cls in (*COMPOSITES, *DECORATORS):
        assert registry[cls.yaml_name] is cls
    composites = {n for n, _ in registry.control("composite")}
    assert {n for n in composites if not n.startswith("bt_")} == {
        "sequence",
        "reactive_sequence",
        "selector",
        "reactive_selector",
        "parallel",
    }
    # BT.CPP 4's own composites, with BT.CPP's semantics (docs/btcpp.md)
    assert {"bt_sequence", "bt_sequence_with_memory", "bt_fallback", "bt_if_then_else", "bt_switch6"} <= composites
    assert "delay" in {n for n, _ in registry.control("decorator")}


@pytest.mark.parametrize(
    "name, words",
    [
        ("parallel", ["success_on_one", "synchronise", "A composite"]),
        ("repeat", ["times", "until: NODE", "forever"]),
        ("delay", ["seconds", "simulated"]),
    ],
)
def test_cli_documents_control_nodes(name, words):
    out = CliRunner().invoke(main, ["behaviours", name]).output
    for word in words:
        assert word in out, (name, word)


def test_schema_describes_control_nodes_from_their_parameter_models():
    props = mission_schema()["$defs"]["node"]["anyOf"][1]["properties"]
    parallel = props["parallel"]["anyOf"][1]["properties"]
    assert parallel["policy"]["enum"] == ["success_on_all", "success_on_one"]
    assert props["delay"]["required"] == ["do", "seconds"]
    assert set(props["repeat"]["properties"]) == {"name", "times", "until", "do"}


def test_a_plugin_decorator_is_one_class(tmp_path):
    (tmp_path / "twice.py").write_text(
        textwrap.dedent('''
        import py_trees
        from thymio_bt.behaviours import ControlNode

        class Twice(ControlNode):
            """Run the child two times in a row."""
            yaml_name = "twice"
            short_form = True

            @classmethod
            def build(cls, name, params, children, ctx):
                return py_trees.decorators.Repeat(name=name, child=children[0], num_success=2)
        ''')
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [twice.py]\ntree: {twice: {Wait: {seconds: 1}}}\n")
    result = Run(load_mission(mission)).run()
    assert result.status == "SUCCESS"
    assert sum(1 for e in result.events if e["kind"] == "behaviour_start") == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("maze: arena\nstart: centre\nplugins: [twice.py]\ntree: {twice: {do: Stop, times: 3}}\n")
    with pytest.raises(UserError, match="unknown key 'times' in a twice"):
        load_mission(bad)


@pytest.mark.parametrize(
    "tree, message",
    [
        ("{delay: {do: Stop}}", "delay needs 'seconds'"),
        ("{delay: {seconds: -1, do: Stop}}", "greater than 0"),
        ("{delay: Stop}", "delay needs a mapping with seconds, do"),
        ("{guard: {do: Stop}}", "guard needs a condition"),
        ("{repeat: {times: 2, until: Stop, do: Stop}}", "repeat takes either times or until, not both"),
        ("{until: {status: maybe, do: Stop}}", "until status must be success or failure"),
    ],
)
def test_control_node_parameters_are_checked_where_they_are_written(tmp_path, tree, message):
    path = tmp_path / "m.yaml"
    path.write_text(f"maze: arena\nstart: centre\ntree: {tree}\n")
    with pytest.raises(UserError) as info:
        load_mission(path)
    assert message in str(info.value) and f"{path}:3:" in str(info.value)


def test_control_node_base_is_not_a_py_trees_behaviour_but_can_be():
    from thymio_bt.behaviours.flow.decorators import Delay, Invert

    assert issubclass(Delay, py_trees.decorators.Decorator) and issubclass(Delay, ControlNode)
    assert not issubclass(Invert, py_trees.behaviour.Behaviour)
