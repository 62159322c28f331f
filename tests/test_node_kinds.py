"""A node kind is one class: its facts (family, what it makes of its child's outcomes, whether it
stops its child, its BT.CPP node, its symbol) are declared on it, and every tool reads them there.

The decorators below are defined in this module and registered as a plugin registers them (a
mission's ``plugins: [module:Class]``); lint's rules, the BT.CPP export and read back, the JSON
Schema and the terminal tree find them without any change to the package.
"""

import math
import re
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status

from thymio_bt.analysis.schema import mission_schema
from thymio_bt.analysis.tree_rules import TreeRules, is_condition
from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour
from thymio_bt.behaviours.flow.node import SWAP, ControlNode, F, S
from thymio_bt.btcpp.export import mission_xml
from thymio_bt.mission.loader import load_mission
from thymio_bt.plan.registry import default_registry
from thymio_bt.run.coverage import Coverage
from thymio_bt.viz.graph import plan_dot
from thymio_bt.viz.terminal import coverage_text


class Veto(ControlNode):
    """Report FAILURE once the child ends, whatever it ends with (RUNNING stays RUNNING)."""

    yaml_name = "veto"
    short_form = True
    example = "e.g. 'veto: Stop'"
    outcome = {S: F, F: F}
    halts, passes_on = False, True
    symbol = "-x-"

    @classmethod
    def build(cls, name, params, children, ctx):
        """py_trees' SuccessIsFailure of the child."""
        return py_trees.decorators.SuccessIsFailure(name=name, child=children[0])


class Negate(ControlNode):
    """Swap SUCCESS and FAILURE of the child: BT.CPP's Inverter, under another name."""

    yaml_name = "negate"
    short_form = True
    example = "e.g. 'negate: WallAhead'"
    outcome, halts, passes_on = SWAP, False, True
    btcpp_id = "Inverter"

    @classmethod
    def build(cls, name, params, children, ctx):
        """py_trees' Inverter of the child."""
        return py_trees.decorators.Inverter(name=name, child=children[0])


class Repeat(RobotBehaviour):
    """A plugin's behaviour that happens to have the name of a BT.CPP built-in: succeed at once."""

    Params = BehaviourParams

    def step(self):
        """Done."""
        return Status.SUCCESS


class Refuse(RobotBehaviour):
    """A plugin's action that always fails at once, and says so to the lint."""

    Params = BehaviourParams
    always, instant = "F", True

    def step(self):
        """No."""
        return Status.FAILURE


class BumperParams(BehaviourParams):
    """How far the plugin's bumper feels."""

    reach: float = 0.05


class Bumper(RobotBehaviour):
    """A plugin's condition that, inverted, says the way ahead is clear to its ``reach``."""

    Params = BumperParams
    condition = True

    @classmethod
    def clear_ahead(cls, params):
        """Inverted, nothing within ``reach``."""
        return params.reach

    def step(self):
        """Nothing felt."""
        return Status.FAILURE


class Crawl(RobotBehaviour):
    """A plugin's action that drives forward for ever without looking."""

    Params = BehaviourParams
    moves = True

    @classmethod
    def drives_forward(cls, params):
        """No bound."""
        return math.inf

    def step(self):
        """Forward."""
        self.robot.drive(0.05, 0.0)
        return Status.RUNNING


def _mission(tmp_path, tree: str):
    """A mission with this module's decorators as plugins, loaded (their code run)."""
    path = tmp_path / "kinds.yaml"
    path.write_text(f"maze: arena\nstart: centre\nplugins: [{__name__}:Veto, {__name__}:Negate]\ntree:\n{tree}")
    return load_mission(path, run_plugins=True)


VETOED = "  sequence:\n    - veto: Stop\n    - MoveDistance: {distance: 10cm}\n"


def test_a_new_decorator_is_not_in_the_package():
    assert "veto" not in default_registry() and "negate" not in default_registry()


def test_lint_reads_what_a_new_decorator_makes_of_its_child(tmp_path):
    rules = TreeRules(_mission(tmp_path, VETOED))
    veto = rules.tree.children[0]
    assert rules.outcomes(veto) == {F}  # Stop always succeeds, the veto makes it a failure
    [finding] = rules.findings()
    assert finding.rule == "unreachable"
    assert finding.message == "'MoveDistance' never runs: 'veto' before it in sequence 'sequence' always fails"


def test_thymio_bt_lint_with_plugins_knows_a_new_decorator(tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    _mission(tmp_path, VETOED)
    found = CliRunner().invoke(main, ["lint", str(tmp_path / "kinds.yaml"), "--plugins"])
    assert found.exit_code == 1 and "[unreachable] 'MoveDistance' never runs" in found.output


def test_lint_reads_what_a_plugin_s_leaf_declares_it_always_ends_with(tmp_path):
    path = tmp_path / "leaf.yaml"
    tree = "{sequence: [Refuse, {MoveDistance: {distance: 10cm}}]}"
    path.write_text(f"maze: arena\nstart: centre\nplugins: [{__name__}:Refuse]\ntree: {tree}\n")
    [finding] = TreeRules(load_mission(path, run_plugins=True)).findings()
    assert finding.message == "'MoveDistance' never runs: 'Refuse' before it in sequence 'sequence' always fails"


def test_lint_takes_a_new_inverter_for_one(tmp_path):
    """checked-once looks through inverters: a kind whose outcome swaps its child's is one."""
    tree = "  sequence:\n    - negate: {WallAhead: {distance: 8cm}}\n    - MoveDistance: {distance: 1m}\n"
    [finding] = TreeRules(_mission(tmp_path, tree)).findings()
    assert finding.rule == "checked-once" and "inverted: nothing within 0.08 m ahead" in finding.message


def test_lint_reads_the_way_ahead_facts_a_plugin_s_leaves_declare(tmp_path):
    """checked-once reads what a condition vouches for and how far an action drives from their
    classes: a plugin's pair is found as WallAhead and MoveDistance are, its fact read with its values."""
    path = tmp_path / "leaves.yaml"
    tree = "{sequence: [{invert: {Bumper: {reach: 0.07}}}, Crawl]}"
    path.write_text(f"maze: arena\nstart: centre\nplugins: [{__name__}:Bumper, {__name__}:Crawl]\ntree: {tree}\n")
    mission = load_mission(path, run_plugins=True)
    assert "Bumper" not in default_registry() and is_condition(mission.registry.get("Bumper"))
    [finding] = TreeRules(mission).findings()
    assert finding.rule == "checked-once"
    assert finding.message.startswith("'Bumper' (inverted: nothing within 0.07 m ahead) is checked once, then 'Crawl'")
    assert "drives with no bound" in finding.message
    xml = mission_xml(mission, tmp_path / "leaves.xml")
    assert '<Condition ID="Bumper">' in xml and '<Action ID="Crawl"' in xml  # Groot2's palette reads it too


def test_lint_knows_a_new_decorator_cannot_stop_an_endless_loop(tmp_path):
    tree = "  veto: {repeat: {times: forever, do: Stop}}\n"
    assert [f.rule for f in TreeRules(_mission(tmp_path, tree)).findings()] == ["forever"]


def test_the_btcpp_export_writes_a_new_decorator_as_its_class_says(tmp_path):
    tree = "  sequence:\n    - veto: Stop\n    - negate: WallAhead\n"
    xml = mission_xml(_mission(tmp_path, tree), tmp_path / "kinds.xml")
    assert '<veto name="veto" _thymio="veto" _uid="2">' in xml  # no BT.CPP node: its own, declared in the model
    assert '<Decorator ID="veto" />' in xml
    assert '<Inverter name="negate" _thymio="negate" _uid="4">' in xml  # BT.CPP's Inverter, marked as ours
    assert 'ID="negate"' not in xml  # a BT.CPP built-in: nothing to declare


def test_a_new_decorator_reads_back_from_its_export(tmp_path):
    mission = _mission(tmp_path, VETOED)
    (tmp_path / "kinds.xml").write_text(mission_xml(mission, tmp_path / "kinds.xml"))
    again = load_mission(tmp_path / "kinds.xml", run_plugins=True)
    veto = again.tree.children[0]
    assert (veto.kind, [c.behaviour for c in veto.children]) == ("veto", ["Stop"])


def test_the_json_schema_describes_a_new_decorator(tmp_path):
    schema = mission_schema(_mission(tmp_path, VETOED).registry)
    veto = next(
        node["properties"]["veto"] for node in schema["$defs"]["node"]["anyOf"] if "veto" in node.get("properties", {})
    )
    assert veto["description"] == Veto.__doc__.splitlines()[0]
    assert {"$ref": "#/$defs/node"} in veto["anyOf"]  # its short form, veto: CHILD


@pytest.mark.parametrize("draw", ["text", "dot"])
def test_the_terminal_tree_draws_a_new_decorator_with_its_symbol(tmp_path, draw):
    mission = _mission(tmp_path, VETOED)
    if draw == "text":
        text = coverage_text(Coverage.of(mission.tree).to_json(), registry=mission.registry)
        assert text.splitlines()[2].split() == ["-x-", "veto", "never", "ticked"]
    else:
        assert 'label="veto", shape=ellipse' in plan_dot(mission.tree, mission.registry)


def test_every_built_in_kind_declares_its_btcpp_node_once():
    """A BT.CPP ID names one of thymio-bt's kinds at most (the reader maps it back by its class)."""
    ours = [
        cls.btcpp_id
        for _, cls in default_registry().items()
        if getattr(cls, "btcpp_id", "") and not getattr(cls, "btcpp_native", True)
    ]
    assert len(ours) == len(set(ours)) and "Fallback" in ours


def test_a_node_named_as_any_bt_cpp_built_in_is_exported_apart_and_read_back_as_itself(tmp_path):
    """BT.CPP's names come from its node kinds' classes: Repeat was missing from a hand-written list,
    so a plugin's Repeat was written <Repeat> and read back as BT.CPP's Repeat."""
    path = tmp_path / "named.yaml"
    path.write_text(f"maze: arena\nstart: centre\nplugins: [{__name__}:Repeat]\ntree: {{sequence: [Repeat, Stop]}}\n")
    xml = mission_xml(load_mission(path, run_plugins=True), tmp_path / "named.xml")
    assert '<ThymioRepeat name="Repeat"' in xml
    (tmp_path / "named.xml").write_text(xml)
    again = load_mission(tmp_path / "named.xml", run_plugins=True)
    assert [c.behaviour for c in again.tree.children] == ["Repeat", "Stop"]


def _btcpp_kinds():
    from thymio_bt.btcpp.runtime.control import BTCPP_CONTROL

    return {cls.yaml_name: cls for cls in BTCPP_CONTROL}


def test_a_btcpp_kind_with_a_yaml_twin_has_its_facts_from_the_twin_s_class():
    """BT.CPP's Sequence is the lint's and the pictures' sequence: its family, symbol, outcome...
    are declared once, on the YAML kind, and a change there reaches both."""
    from thymio_bt.btcpp.runtime.control import TWIN_FACTS

    kinds = _btcpp_kinds()
    twins = {name: cls.like.yaml_name for name, cls in kinds.items() if cls.like is not None}
    assert twins == {
        **dict.fromkeys(("bt_sequence", "bt_sequence_with_memory"), "sequence"),
        "bt_reactive_sequence": "reactive_sequence",
        "bt_fallback": "selector",
        "bt_reactive_fallback": "reactive_selector",
        **dict.fromkeys(("bt_parallel", "bt_parallel_all"), "parallel"),
        "bt_inverter": "invert",
        "bt_force_success": "force_success",
        "bt_force_failure": "force_failure",
        "bt_repeat": "repeat",
        "bt_retry_until_successful": "retry",
        "bt_run_once": "one_shot",
        "bt_timeout": "timeout",
        "bt_delay": "delay",
    }
    for name, cls in kinds.items():
        if cls.like is not None:  # the mapped decorators' outcome is read from their tick's map: the same
            assert {f: getattr(cls, f) for f in TWIN_FACTS} == {f: getattr(cls.like, f) for f in TWIN_FACTS}, name
    plain = [cls for cls in kinds.values() if cls.like is None]
    assert all("like" in cls.__dict__ for cls in plain)  # declared none, not forgotten

    class Dotted(kinds["bt_sequence"]):  # a twin's fact changed on the twin reaches the BT.CPP kind
        like = type("Drawn", (kinds["bt_sequence"].like,), {"symbol": "{.}"})

    assert Dotted.symbol == "{.}" and Dotted.family == "sequence"


def test_docs_btcpp_names_each_twin_as_the_nearest_yaml_node():
    """docs/btcpp.md's table says, for each BT.CPP node, the nearest YAML node: the class's twin."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "btcpp.md").read_text()
    kinds = _btcpp_kinds()
    seen = set()
    for row in doc.splitlines():
        cells = row.split(" | ")
        if len(cells) != 4 or "bt_" not in cells[1]:
            continue
        nearest = [re.split(r"[: ]", name)[0] for name in re.findall(r"`([^`]+)`", cells[3])]
        for i, name in enumerate(re.findall(r"`(bt_\w+)`", cells[1])):
            cls = kinds.get(name)
            if cls is not None and cls.like is not None:
                assert nearest[i : i + 1] == [cls.like.yaml_name], row
                seen.add(name)
    assert seen == {name for name, cls in kinds.items() if cls.like is not None}
