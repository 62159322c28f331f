"""XML missions written with BT.CPP 4's built-ins run with BT.CPP's semantics (#33)."""

import random
import re
import subprocess
import sys
from pathlib import Path

import pytest
from _require import module

ROOT = Path(__file__).resolve().parents[1]

MISSION = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <ThymioMission maze="{maze}" start="centre" time_limit="20"/>
  <BehaviorTree ID="Main">
    <Sequence>
      <Repeat num_cycles="2">
        <SequenceWithMemory>
          <MoveDistance distance="0.05"/>
          <TurnAngle angle="1.5707963"/>
        </SequenceWithMemory>
      </Repeat>
      <Timeout msec="1500"{extra}><Wait seconds="5"/></Timeout>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _write(tmp_path, extra=""):
    path = tmp_path / "m.xml"
    path.write_text(MISSION.format(maze=(ROOT / "mazes/arena.yaml").resolve(), extra=extra))
    return path


def test_bt_cpp_built_ins_are_read_as_bt_cpp_nodes(tmp_path):
    from thymio_bt.btcpp.xml_reader import read_xml_mission

    tree = read_xml_mission(_write(tmp_path))["tree"]
    children = tree["bt_sequence"]["children"]
    assert list(children[0]) == ["bt_repeat"] and children[0]["bt_repeat"]["num_cycles"] == "2"
    assert list(children[0]["bt_repeat"]["do"]) == ["bt_sequence_with_memory"]
    assert children[1]["bt_timeout"]["msec"] == "1500"


def test_a_timeout_counts_milliseconds_of_simulated_time(tmp_path):
    from thymio_bt.mission.loader import load_mission
    from thymio_bt.run.runner import Run

    report = Run(load_mission(_write(tmp_path)), seed=0).run().report()
    assert report["status"] == "FAILURE" and report["failed_path"] == "bt_sequence"
    first = Run(load_mission(_write(tmp_path)), seed=0).run().report()
    assert first["sim_time"] == report["sim_time"]  # deterministic: no wall clock


def test_a_script_error_is_a_file_line_error_before_the_run(tmp_path):
    path = _write(tmp_path, extra=' _skipIf="x == "')
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt.cli", "validate", str(path)], capture_output=True, text=True
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"{path}:11:" in done.stderr and "invalid script 'x == '" in done.stderr and "hint" in done.stderr


SCRIPTED = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <ThymioMission maze="{maze}" start="centre" time_limit="20"/>
  <BehaviorTree ID="Main">
    <Sequence>
      <Script code="laps := 0; side := 'left'"/>
      <Repeat num_cycles="3">
        <Sequence>
          <MoveDistance distance="0.05" _onSuccess="laps += 1"/>
          <Switch2 variable="{{side}}" case_1="left" case_2="right">
            <TurnAngle angle="1.5707963"/>
            <TurnAngle angle="-1.5707963"/>
            <AlwaysFailure/>
          </Switch2>
        </Sequence>
      </Repeat>
      <ScriptCondition code="laps == 3"/>
      <Precondition if="laps > 2"><Sleep msec="500"/></Precondition>
      <AlwaysSuccess _skipIf="laps == 3" _post="done := true"/>
      <UnsetBlackboard key="side"/>
      <SetBlackboard output_key="copy" value="{{laps}}"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def test_a_groot2_tree_with_scripts_runs_and_exports_to_bt_cpp_and_back(tmp_path):
    from _require import module
    from test_btcpp_export import _stub_tree

    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.mission.loader import load_mission
    from thymio_bt.run.runner import Run

    bt = module("behaviortreepy")
    path = tmp_path / "groot.xml"
    path.write_text(SCRIPTED.format(maze=(ROOT / "mazes/arena.yaml").resolve()))
    out = tmp_path / "out.xml"
    out.write_text(mission_xml(load_mission(path), out))
    text = out.read_text()
    assert "<Switch2 " in text and '_skipIf="laps == 3"' in text and 'timeout="' not in text.split("<Script ")[1][:80]
    tree = _stub_tree(bt, text)
    assert tree.tick_once().name == "RUNNING"
    reports = [Run(load_mission(p), seed=0).run().report() for p in (path, out)]
    for report in reports:
        report.pop("wall_time"), report.pop("real_time_factor")
    assert reports[0] == reports[1] and reports[0]["status"] == "SUCCESS"


def test_a_bt_cpp_name_in_yaml_gets_the_hint_of_its_thymio_bt_node():
    from thymio_bt.btcpp.export import yaml_hint

    assert yaml_hint("Fallback") == "Fallback is `selector` here (BT.CPP's own Fallback, tick for tick: `bt_fallback`)"
    assert yaml_hint("Sequence").startswith("Sequence is `sequence` here")


# ---------------------------------------------------------------- <SubTree> ports and scopes

KEYS = ("a", "b", "c", "d", "_p")
CHECKED = ("a", "b", "c", "d", "_p", "s")


def _document(main: str, trees: str = "", models: str = "") -> str:
    """A BT.CPP document whose main tree first sets a, b, c and _p."""
    body = f'<Sequence><Script code="a := 1; b := 10; c := 100; _p := 5"/>{main}</Sequence>'
    model = f"<TreeNodesModel>{models}</TreeNodesModel>" if models else ""
    return (
        f'<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Main">{body}</BehaviorTree>'
        f"{trees}{model}</root>"
    )


def _values(get):
    """The checked root entries through ``get(key)`` (None: no entry), a number (or the text of
    one: BT.CPP converts) as a float."""
    out = {}
    for key in CHECKED:
        value = get(key)
        if value is not None:
            try:
                out[key] = float(value)
            except ValueError:
                out[key] = value
    return out


def _run_btcpp(bt, xml):
    """BT.CPP's status after one tick ("ERROR" when it throws) and its root entries."""
    tree = bt.BehaviorTreeFactory().create_tree_from_text(xml)
    try:
        status = tree.tick_once().name
    except RuntimeError:
        status = "ERROR"
    board = tree.root_blackboard()
    keys = set(board.get_keys())

    def get(key):
        if key not in keys:
            return None
        for getter in (board.get_string, board.get_double):
            try:
                return getter(key)
            except Exception:
                continue
        return None

    return status, _values(get)


def _run_here(xml, folder):
    """thymio-bt's status after one tick ("ERROR" when a script fails, as BT.CPP throws) and its
    root entries; a UserError's message when the file is refused."""
    from types import SimpleNamespace

    from py_trees.blackboard import Blackboard

    from thymio_bt.behaviours.base import FailureCode
    from thymio_bt.behaviours.flow.ticking import tick
    from thymio_bt.errors import UserError
    from thymio_bt.mission.build import build_tree
    from thymio_bt.mission.loader import load_mission

    maze = (ROOT / "mazes/arena.yaml").resolve()
    path = folder / "scoped.xml"
    path.write_text(xml.replace("<BehaviorTree ", f'<ThymioMission maze="{maze}" start="centre"/><BehaviorTree ', 1))
    try:
        mission = load_mission(path)
    except UserError as exc:
        return str(exc)
    Blackboard.storage.clear()
    ctx = SimpleNamespace(robot=SimpleNamespace(exists=lambda: False), now=lambda: 0.0, collision_count=lambda: 0)
    root = build_tree(mission.tree, ctx, mission.registry)
    try:
        tick(root)
        status = root.status.name
    except ValueError:  # a condition's script failed
        status = "ERROR"
    if any(getattr(n, "failure", None) and n.failure[0] == FailureCode.EXCEPTION.value for n in root.iterate()):
        status = "ERROR"
    values = _values(lambda key: Blackboard.storage.get("/" + key))
    Blackboard.storage.clear()
    return status, values


SCOPED = {
    "a subtree's keys are its own": (
        '<SubTree ID="S"/><Script code="@s := \'after\'"/>',
        '<BehaviorTree ID="S"><Script code="a := 5; d := 2"/></BehaviorTree>',
        "",
    ),
    "a subtree cannot read the parent's keys": (
        '<SubTree ID="S"/>',
        '<BehaviorTree ID="S"><Script code="d := a"/></BehaviorTree>',
        "",
    ),
    "a remapped port is the parent's entry": (
        '<SubTree ID="S" x="{a}" y="{=}"/>',
        '<BehaviorTree ID="S"><Script code="x := x + 5; y := y * 2; d := 1"/></BehaviorTree>',
        "",
    ),
    "a literal port is read as its text": (
        '<SubTree ID="S" k="7"/>',
        '<BehaviorTree ID="S"><Sequence><ScriptCondition code="k == \'7\'"/><Script code="@s := k"/></Sequence>'
        "</BehaviorTree>",
        "",
    ),
    "_autoremap shows the parent's keys but the private ones": (
        '<SubTree ID="S" _autoremap="true"/>',
        '<BehaviorTree ID="S"><Script code="a := a + 1; d := 3; _p := 9; _q := 4"/></BehaviorTree>',
        "",
    ),
    "UnsetBlackboard removes the instance's own entries only": (
        '<SubTree ID="S" x="{a}" _autoremap="1"/><SubTree ID="S" x="{c}"/>',
        '<BehaviorTree ID="S"><Sequence><UnsetBlackboard key="x"/><UnsetBlackboard key="b"/>'
        '<UnsetBlackboard key="@c"/></Sequence></BehaviorTree>',
        "",
    ),
    "each instance has its own entries": (
        '<SubTree ID="S" o="{a}"/><SubTree ID="S" o="{b}"/>',
        '<BehaviorTree ID="S"><Sequence><Script code="n := 0"/><Script code="n += 1; o := o + n"/></Sequence>'
        "</BehaviorTree>",
        "",
    ),
    "@key is the main tree's entry at any depth": (
        '<SubTree ID="S" x="{@b}"/>',
        '<BehaviorTree ID="S"><SubTree ID="T"/></BehaviorTree>'
        '<BehaviorTree ID="T"><Script code="@b := @b + 3; @d := 1"/></BehaviorTree>',
        "",
    ),
    "nested remappings chain up": (
        '<SubTree ID="S" x="{a}"/>',
        '<BehaviorTree ID="S"><SubTree ID="T" y="{x}"/></BehaviorTree>'
        '<BehaviorTree ID="T"><Script code="y := y + 10"/></BehaviorTree>',
        "",
    ),
    "a model's defaults set the ports not written": (
        '<SubTree ID="S"/><SubTree ID="S" k="8" o="{c}"/>',
        '<BehaviorTree ID="S"><Sequence><Script code="@s := k"/><Script code="o := o + 1"/></Sequence></BehaviorTree>',
        '<SubTree ID="S"><input_port name="k" default="7"/><inout_port name="o" default="{b}"/></SubTree>',
    ),
    "Switch and SetBlackboard read remapped and literal ports": (
        '<Script code="s := \'y\'"/><SubTree ID="S" v="{s}" c2="y" o="{d}"/>',
        '<BehaviorTree ID="S"><Switch2 variable="{v}" case_1="x" case_2="{c2}"><AlwaysFailure/>'
        '<SetBlackboard value="{v}" output_key="o"/><AlwaysFailure/></Switch2></BehaviorTree>',
        "",
    ),
    "a SubTree's condition attributes are read in the parent's scope": (
        '<SubTree ID="S" x="{b}" _skipIf="a == 2" _onSuccess="a := x"/>',
        '<BehaviorTree ID="S"><Script code="x := 4; a := 2" _post="x += 1"/></BehaviorTree>',
        "",
    ),
}


@pytest.mark.parametrize("case", sorted(SCOPED))
def test_subtree_ports_and_scopes_run_as_in_behaviortree_cpp(case, tmp_path):
    bt = module("behaviortreepy")
    xml = _document(*SCOPED[case])
    expected, got = _run_btcpp(bt, xml), _run_here(xml, tmp_path)
    assert expected == got


STATEMENTS = [
    "{x} := {y} + 1",
    "{x} := {y} * 2",
    "{x} := 7",
    "{x} += 3",
    "@{x} := {y} + 100",
]
CHECKS_ON = ["{x} > 5", "{x} == {y}", "{x} &lt; 50"]


def _scoped_tree(rng, index, count):
    """The body of subtree ``index`` of ``count`` (or the main tree's, ``index`` -1): scripts over
    the keys, conditions, UnsetBlackboard, a literal port's check, and uses of the later subtrees
    with random ports (remapped, {=}, {@key}, literal) and _autoremap."""
    created = rng.sample(KEYS, rng.randint(1, 4)) if index >= 0 else ["d"] * (rng.random() < 0.7)
    parts = [f'<Script code="{"; ".join(f"{k} := {rng.randint(0, 9)}" for k in created)}"/>'] if created else []
    for _ in range(rng.randint(1, 4)):
        roll = rng.random()
        x, y = rng.choice(KEYS), rng.choice(KEYS)
        if roll < 0.35:
            parts.append(f'<Script code="{rng.choice(STATEMENTS).format(x=x, y=y)}"/>')
        elif roll < 0.5:
            parts.append(
                f'<ForceSuccess><ScriptCondition code="{rng.choice(CHECKS_ON).format(x=x, y=y)}"/></ForceSuccess>'
            )
        elif roll < 0.55:
            parts.append(f'<UnsetBlackboard key="{rng.choice([x, "@" + x])}"/>')
        elif roll < 0.62 and index >= 0:
            parts.append('<ForceSuccess><Script code="@s := k"/></ForceSuccess>')
        elif index + 1 < count:
            target = rng.randint(index + 1, count - 1)
            ports = []
            for port in ("a", "b", "x", "k"):
                choice = rng.random()
                if port == "k" and choice < 0.5:
                    ports.append(f'k="{rng.choice(["7", "8"])}"')
                elif port != "k" and choice < 0.4:
                    ports.append(f'{port}="{rng.choice(["{a}", "{b}", "{c}", "{d}", "{@a}", "{=}", "{x}"])}"')
            if rng.random() < 0.4:
                ports.append(f'_autoremap="{rng.choice(["true", "false"])}"')
            parts.append(f'<SubTree ID="S{target}" {" ".join(ports)}/>')
    parts = parts or ['<Script code="d := 1"/>']
    composite = rng.choice(["Sequence", "Sequence", "Fallback"])
    return f"<{composite}>{''.join(parts)}</{composite}>"


def random_scoped_document(rng):
    """A random document of a main tree and up to four subtrees using each other (acyclic)."""
    count = rng.randint(1, 4)
    trees = "".join(f'<BehaviorTree ID="S{i}">{_scoped_tree(rng, i, count)}</BehaviorTree>' for i in range(count))
    main = _scoped_tree(rng, -1, count)
    models = ""
    if rng.random() < 0.3:
        models = f'<SubTree ID="S{rng.randrange(count)}"><input_port name="k" default="9"/></SubTree>'
    return _document(main, trees, models)


SCOPED_TREES = 600


def test_generated_subtree_scopes_run_as_in_behaviortree_cpp(tmp_path):
    bt = module("behaviortreepy")
    differences, compared, errors = [], 0, 0
    for seed in range(SCOPED_TREES):
        xml = random_scoped_document(random.Random(seed))
        got = _run_here(xml, tmp_path)
        if isinstance(got, str):  # refused: only for a literal port a node writes
            assert "sets to the literal" in got, (seed, got)
            continue
        compared += 1
        expected = _run_btcpp(bt, xml)
        if expected[0] == "ERROR" == got[0]:  # a script failed: BT.CPP stops the tick there, a
            errors += 1  # failing script here fails its node and the tick goes on (docs/btcpp.md)
            continue
        if expected != got:
            differences.append((seed, xml, expected, got))
    assert not differences, (len(differences), differences[:1])
    assert compared > SCOPED_TREES * 9 // 10 and errors < compared // 2


LEGS = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <ThymioMission maze="{maze}" start="centre" time_limit="30"/>
  <BehaviorTree ID="Main">
    <Sequence>
      <Script code="quarter := 1.5707963; back := -0.05; legs := 0"/>
      <SubTree ID="Leg" name="out" d="0.05" a="{{quarter}}" n="{{legs}}"/>
      <SubTree ID="Leg" name="back" d="{{back}}" a="-1.5707963" n="{{legs}}"/>
      <ScriptCondition code="legs == 2"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Leg">
    <Sequence>
      <MoveDistance distance="{{d}}"/>
      <TurnAngle angle="{{a}}"/>
      <SetBlackboard key="turn" value="left"/>
      <Script code="n += 1; done := true"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def test_a_subtree_with_ports_runs_in_a_mission_once_per_use(tmp_path):
    from thymio_bt.btcpp.xml_reader import read_xml_mission
    from thymio_bt.mission.loader import load_mission
    from thymio_bt.run.runner import Run

    path = tmp_path / "legs.xml"
    path.write_text(LEGS.format(maze=(ROOT / "mazes/arena.yaml").resolve()))
    out, back = read_xml_mission(path)["tree"]["bt_sequence"]["children"][1:3]
    assert out.subtree_use == back.subtree_use == "Leg" and out["bt_sequence"]["name"] == "out"
    first, second = (leg["bt_sequence"]["children"] for leg in (out, back))
    assert first[0]["MoveDistance"]["distance"] == 0.05 and first[1]["TurnAngle"]["angle"] == "bb:quarter"
    assert second[0]["MoveDistance"]["distance"] == "bb:back" and second[1]["TurnAngle"]["angle"] == -1.5707963
    assert (first[2]["SetBlackboard"]["key"], second[2]["SetBlackboard"]["key"]) == ("__1_Leg__turn", "__2_Leg__turn")
    assert second[3]["bt_script"]["code"] == "legs += 1; __2_Leg__done := true"
    report = Run(load_mission(path), seed=0).run().report()
    assert report["status"] == "SUCCESS", report


def test_a_literal_port_a_node_writes_is_an_error_naming_both_places(tmp_path):
    path = tmp_path / "m.xml"
    path.write_text(LEGS.format(maze=(ROOT / "mazes/arena.yaml").resolve()).replace('n="{legs}"/>', 'n="0"/>', 1))
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt.cli", "validate", str(path)], capture_output=True, text=True
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"{path}:16:7: this node writes 'n', which <SubTree ID=\"Leg\"> sets to the literal '0' ({path}:6:7)" in (
        done.stderr
    )


@pytest.mark.parametrize(
    "subtree, model, message",
    [
        ('<SubTree ID="S"/>', '<input_port name="k"/>', "does not set its port 'k', which has no default"),
        ('<SubTree ID="S" _autoremap="yes"/>', "", '_autoremap="yes" is not true or false'),
        ('<SubTree ID="S"/>', "<input_port/>", "a port of a <SubTree> model has no name"),
    ],
)
def test_subtree_ports_bt_cpp_refuses_are_refused_here(subtree, model, message, tmp_path):
    from thymio_bt.btcpp.xml_reader import read_xml_mission
    from thymio_bt.errors import UserError

    xml = _document(
        subtree, '<BehaviorTree ID="S"><AlwaysSuccess/></BehaviorTree>', f'<SubTree ID="S">{model}</SubTree>'
    )
    path = tmp_path / "m.xml"
    path.write_text(xml)
    with pytest.raises(UserError, match=re.escape(message)):
        read_xml_mission(path)
    if "no name" not in message:
        with pytest.raises(RuntimeError):
            module("behaviortreepy").BehaviorTreeFactory().create_tree_from_text(xml)


def test_the_reader_takes_each_port_s_role_from_the_node_s_model_not_from_its_name():
    from pydantic import BaseModel, Field

    from thymio_bt.btcpp.runtime.scripted import Code
    from thymio_bt.btcpp.xml_tree import _roles
    from thymio_bt.inputs.fields import BlackboardKey, Entry, ScriptText, port_roles

    assert _roles("bt_set_blackboard") == {"output_key": Entry()}
    assert _roles("bt_unset_blackboard") == {"key": Entry("removed")}
    assert _roles("bt_script") == {"code": ScriptText()} and _roles("bt_precondition") == {"if": ScriptText()}
    assert _roles("ChooseTurn") == {"key": Entry()} and _roles("SetBlackboard") == {"key": Entry()}
    assert _roles("MoveDistance") == {} and _roles("NoSuchNode") == {}

    class Params(BaseModel):
        entry: BlackboardKey = "x"
        program: Code = "a := 1"
        key: str = Field("k", description="a blackboard key, in words only")

    assert port_roles(Params) == {"entry": Entry(), "program": ScriptText()}
