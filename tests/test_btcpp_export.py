"""`tree --btcpp` exports that BehaviorTree.CPP 4 itself (behaviortreepy) loads and runs with only
stub leaves registered, and that run back here to the identical report (#33)."""

import json
import re
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from _require import module

ROOT = Path(__file__).resolve().parents[1]

MISSIONS = sorted((ROOT / "missions").glob("*.yaml"))
PLUGIN_MISSION = ROOT / "examples/spin_until_clear.yaml"


def _export(mission: Path, out: Path) -> str:
    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.mission.loader import load_mission

    text = mission_xml(load_mission(mission, run_plugins=False), out)
    out.write_text(text)
    return text


def _stub_tree(bt, xml: str):
    """The export as a BT.CPP tree: every TreeNodesModel node registered as a stub (actions RUNNING
    once then SUCCESS, conditions alternating), their ports dropped (stubs declare none)."""
    root = ET.fromstring(xml)
    model = root.find("TreeNodesModel")
    assert model is not None
    leaves = {entry.get("ID"): entry.tag for entry in model}
    assert "Control" not in leaves.values(), "an export needs no custom control node"
    factory = bt.BehaviorTreeFactory()
    calls: dict[str, int] = {}

    def condition(node):
        calls[node.name()] = calls.get(node.name(), 0) + 1
        return bt.NodeStatus.SUCCESS if calls[node.name()] % 3 == 0 else bt.NodeStatus.FAILURE

    for ident, tag in leaves.items():
        if tag == "Condition":
            factory.register_simple_condition(ident, condition)
        else:
            factory.register_simple_stateful_action(
                ident, lambda node: bt.NodeStatus.RUNNING, lambda node: bt.NodeStatus.SUCCESS
            )
    for element in root.iter():
        if element.tag in leaves:
            for key in [k for k in element.attrib if k not in ("name", "_uid")]:
                del element.attrib[key]
    root.remove(model)
    return factory.create_tree_from_text(ET.tostring(root, encoding="unicode"))


@pytest.mark.parametrize("mission", [*MISSIONS, PLUGIN_MISSION], ids=lambda m: m.stem)
def test_every_export_loads_and_runs_in_behaviortree_cpp_with_stub_leaves(mission, tmp_path):
    bt = module("behaviortreepy")
    xml = _export(mission, tmp_path / "tree.xml")
    assert "RepeatUntil" not in xml
    tree = _stub_tree(bt, xml)
    statuses = [tree.tick_once() for _ in range(60)]
    assert set(statuses) <= {bt.NodeStatus.RUNNING, bt.NodeStatus.SUCCESS, bt.NodeStatus.FAILURE}


def test_a_do_while_condition_with_a_precondition_keeps_its_inverter(tmp_path):
    """A loop's condition that carries BT.CPP's ``_skipIf`` (a bt_conditions node here) is still
    written under the loop's Inverter, so the export reads back as the same loop."""
    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.mission.loader import load_mission

    first = tmp_path / "bonus.xml"
    condition = '<IsDeadEnd name="IsDeadEnd" timeout="60.0" key="turn" _uid="18" />'
    xml = _export(ROOT / "missions/maze_bonus.yaml", first)
    assert condition in xml
    first.write_text(xml.replace(condition, condition.replace(' _uid="18"', ' _skipIf="false" _uid="18"')))
    again = mission_xml(load_mission(first), tmp_path / "again.xml")
    (tmp_path / "again.xml").write_text(again)
    assert re.search(r'<Inverter _onFailure="__until_2 := true" _uid="17">\s*<IsDeadEnd [^>]*_skipIf="false"', again)
    assert load_mission(tmp_path / "again.xml").tree.children[-1].kind == "bt_conditions"


def _uids(xml: str) -> list[tuple[str | None, str, str | None]]:
    """(BehaviorTree ID, tag, _uid) of every node element, tree by tree."""
    root = ET.fromstring(xml)
    return [
        (tree.get("ID"), e.tag, e.get("_uid"))
        for tree in root.iter("BehaviorTree")
        for e in tree.iter()
        if e is not tree
    ]


@pytest.mark.parametrize("mission", MISSIONS, ids=lambda m: m.stem)
def test_every_element_carries_the_uid_behaviortree_cpp_gives_it(mission, tmp_path):
    """Groot2 names nodes by uid: our .btlog and monitor must use BT.CPP's numbering, which counts
    a subtree's nodes after its <SubTree> and a do-while loop's scaffolding. BT.CPP's own FileLogger
    writes the tree with the uids it gave."""
    bt = module("behaviortreepy")
    xml = _export(mission, tmp_path / "tree.xml")
    tree = _stub_tree(bt, xml)
    logger = bt.FileLogger(tree, str(tmp_path / "run.btlog"))
    tree.tick_once()
    logger.flush()
    data = (tmp_path / "run.btlog").read_bytes()
    length = struct.unpack_from("<i", data, len(b"BTCPP4-FileLogger2") + 1)[0]
    logged = data[len(b"BTCPP4-FileLogger2") + 5 :][:length].decode()
    assert _uids(xml) == _uids(logged)


def test_a_plugin_mission_exports_its_plugins_and_runs_back_to_the_identical_report(tmp_path):
    from thymio_bt.mission.loader import load_mission
    from thymio_bt.run.runner import Run

    out = tmp_path / "deep" / "spin.xml"
    out.parent.mkdir()
    xml = _export(PLUGIN_MISSION, out)
    settings = ET.fromstring(xml).find("ThymioMission")
    assert settings is not None
    plugins = json.loads(settings.get("plugins", "[]"))
    assert len(plugins) == 1 and not Path(plugins[0]).is_absolute()  # relative to the output file
    assert (out.parent / plugins[0]).resolve() == (PLUGIN_MISSION.parent / "spin_until_clear.py").resolve()
    assert re.search(r'<Action ID="SpinUntilClear">\s*<input_port name="rate"', xml)
    reports = [Run(load_mission(path), seed=3).run().report() for path in (PLUGIN_MISSION, out)]
    for report in reports:
        report.pop("wall_time"), report.pop("real_time_factor")
    assert reports[0] == reports[1]


def test_a_do_while_loop_is_written_with_built_ins_and_read_back_as_one_repeat(tmp_path):
    from thymio_bt.btcpp.xml_reader import read_xml_mission

    xml = _export(ROOT / "missions/maze_bonus.yaml", tmp_path / "bonus.xml")
    assert '<Sequence name="bonus maze" _thymio="repeat" _uid="2">' in xml
    assert '<Script code="__until_2 := false" _uid="3" />' in xml and '<KeepRunningUntilFailure _uid="5">' in xml
    body = read_xml_mission(tmp_path / "bonus.xml")["tree"]["repeat"]
    assert sorted(body) == ["do", "name", "until"] and "IsDeadEnd" in body["until"]


def test_the_palette_command_writes_the_leaves_groot2_imports(tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    out = tmp_path / "palette.xml"
    result = CliRunner().invoke(main, ["palette", "-o", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert text.startswith('<root BTCPP_format="4">') and '<Action ID="MoveUntilWall">' in text
    assert '<Condition ID="WallAhead">' in text and "Sequence" not in text  # Groot2 has its own built-ins


def test_a_tree_that_keeps_the_palettes_defaults_loads(tmp_path):
    """Each leaf with every port as the palette gives it (its default, or blank as Groot2 leaves a
    port without one): an optional port without a value has no default, never the text 'None'."""
    from thymio_bt.btcpp.export import palette_xml
    from thymio_bt.mission.loader import load_mission
    from thymio_bt.plan.registry import default_registry

    registry = default_registry()
    model = ET.fromstring(palette_xml()).find("TreeNodesModel")
    assert model is not None and 'default="None"' not in palette_xml()
    loaded = []
    for entry in model:
        ident, ports = entry.get("ID"), list(entry.iter("input_port"))
        fields = registry[ident.removeprefix("Thymio") if ident not in registry else ident].Params.model_fields
        if any(fields[p.get("name")].is_required() for p in ports):
            continue  # a port the user must set
        attrs = " ".join(f'{p.get("name")}="{p.get("default", "")}"' for p in ports)
        path = tmp_path / f"{ident}.xml"
        path.write_text(
            '<root BTCPP_format="4" main_tree_to_execute="T"><ThymioMission maze="micromouse_4x4" start="start"/>'
            f'<BehaviorTree ID="T"><{ident} {attrs}/></BehaviorTree></root>'
        )
        load_mission(path)
        loaded.append(ident)
    assert {"MapWalls", "AtTarget", "PlanMove", "WallMapped", "InRegion"} <= set(loaded)  # their cols, rows, rect


def test_an_export_names_a_shipped_maze_by_its_name_and_another_by_its_relative_path(tmp_path, monkeypatch):
    """A shipped maze's path depends on where thymio-bt is installed (site-packages): an export written
    anywhere names it as a mission does, ``two_parts_maze``, and runs from any folder."""
    from click.testing import CliRunner

    from thymio_bt.cli import main
    from thymio_bt.mission.loader import load_mission

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "deep" / "out.xml"
    out.parent.mkdir()
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(main, ["tree", str(root / "missions" / "maze_part1_2.yaml"), "--btcpp", str(out)])
    assert result.exit_code == 0, result.output
    assert 'maze="two_parts_maze"' in out.read_text()
    assert load_mission(out).maze.name == load_mission(root / "missions" / "maze_part1_2.yaml").maze.name
    own = tmp_path / "mine.yaml"
    own.write_text((root / "mazes" / "arena.yaml").read_text())
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: mine.yaml\nstart: centre\ntree: Stop\n")
    assert CliRunner().invoke(main, ["tree", str(mission), "--btcpp", str(out)]).exit_code == 0
    assert 'maze="../mine.yaml"' in out.read_text() and load_mission(out).maze.name == "arena"
