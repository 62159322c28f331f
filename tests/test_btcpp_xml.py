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
