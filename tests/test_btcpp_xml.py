"""XML missions written with BT.CPP 4's built-ins run with BT.CPP's semantics (#33)."""

import subprocess
import sys
from pathlib import Path

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
    path.write_text(MISSION.format(maze=Path("mazes/arena.yaml").resolve(), extra=extra))
    return path


def test_bt_cpp_built_ins_are_read_as_bt_cpp_nodes(tmp_path):
    from thymio_bt.mission.xml_reader import read_xml_mission

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

    from thymio_bt.mission.btcpp import mission_xml
    from thymio_bt.mission.loader import load_mission
    from thymio_bt.run.runner import Run

    bt = module("behaviortreepy")
    path = tmp_path / "groot.xml"
    path.write_text(SCRIPTED.format(maze=Path("mazes/arena.yaml").resolve()))
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
    from thymio_bt.mission.btcpp import yaml_hint

    assert yaml_hint("Fallback") == "Fallback is `selector` here (BT.CPP's own Fallback, tick for tick: `bt_fallback`)"
    assert yaml_hint("Sequence").startswith("Sequence is `sequence` here")
