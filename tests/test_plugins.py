"""User behaviours through a mission's plugins: list, validated and documented like built-ins."""

import sys
from pathlib import Path

import pytest

from thymio_bt.errors import UserError
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]


def test_a_plugin_behaviour_runs_in_a_mission():
    mission = load_mission(f"{ROOT}/examples/spin_until_clear.yaml")
    result = Run(mission).run()
    assert result.status == "SUCCESS"
    assert all(v is None for k, v in result.final_proximity.items() if k.startswith("front"))
    assert [e["name"] for e in result.events if e["kind"] == "behaviour_end"] == ["MoveUntilWall", "SpinUntilClear"]


def test_plugin_parameters_are_validated_like_builtins(tmp_path):
    plugin = (ROOT / "examples/spin_until_clear.py").resolve()
    mission = tmp_path / "m.yaml"
    mission.write_text(
        f"maze: {(ROOT / 'mazes/arena.yaml').resolve()}\nstart: centre\nplugins: [{plugin}]\n"
        "tree:\n  SpinUntilClear: {rate: 9 m}\n"
    )
    with pytest.raises(UserError) as err:
        load_mission(mission)
    problem = err.value.problems[0]
    assert (problem.line, problem.column) == (5, 26)
    assert "angular speed" in problem.message and "got a length" in problem.message


def test_a_missing_plugin_is_a_user_error(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: two_parts_maze\nstart: part1\nplugins: [nope.py, no_such_module:X]\ntree: Stop\n")
    with pytest.raises(UserError) as err:
        load_mission(mission)
    problems = err.value.problems
    assert "plugin file not found: nope.py" in problems[0].message and problems[0].line == 3
    assert "cannot import plugin 'no_such_module:X'" in problems[1].message


def test_a_plugin_behaviour_fails_with_its_own_code(tmp_path):
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    (tmp_path / "lost.py").write_text(
        "from thymio_bt.behaviours import RobotBehaviour\n"
        "class LoseLine(RobotBehaviour):\n"
        "    '''Fail with a code of its own.'''\n"
        "    def step(self):\n"
        "        return self.fail('LINE_LOST', 'no line under the robot')\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [lost.py]\ntree: LoseLine\n")
    result = Run(load_mission(mission)).run()
    assert (result.status, result.code, result.reason) == ("FAILURE", "LINE_LOST", "no line under the robot")


def test_a_plugin_behaviour_prepares_its_blackboard_keys_once(tmp_path):
    """prepare() runs once, when the node is built: its keys serve every restart of the node."""
    (tmp_path / "laps.py").write_text(
        "from py_trees.common import Status\n"
        "from thymio_bt.behaviours import RobotBehaviour\n"
        "class CountLap(RobotBehaviour):\n"
        "    'Add one to the laps on the blackboard.'\n"
        "    needs_robot = False\n"
        "    prepared = 0\n"
        "    def prepare(self):\n"
        "        CountLap.prepared += 1\n"
        "        self.board = self.blackboard('laps', write=('laps',))\n"
        "    def step(self):\n"
        "        laps = self.board.get('laps') + 1 if self.board.exists('laps') else 1\n"
        "        self.board.set('laps', laps)\n"
        "        self.feedback_message = f'{laps} laps, prepared {CountLap.prepared} times'\n"
        "        return Status.SUCCESS\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [laps.py]\ntree: {repeat: {times: 3, do: CountLap}}\n")
    run = Run(load_mission(mission))
    result = run.run()
    assert result.status == "SUCCESS"
    assert [e["status"] for e in result.events if e["kind"] == "behaviour_end"] == ["SUCCESS"] * 3
    assert run.root.children[0].feedback_message == "3 laps, prepared 1 times"


def test_a_plugin_behaviour_returning_no_status_fails_with_a_reason(tmp_path):
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    (tmp_path / "sloppy.py").write_text(
        "from thymio_bt.behaviours import RobotBehaviour\n"
        "class Sloppy(RobotBehaviour):\n"
        "    '''Forgets to return a status.'''\n"
        "    def step(self):\n"
        "        pass\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [sloppy.py]\ntree: Sloppy\n")
    result = Run(load_mission(mission)).run()
    assert (result.status, result.code) == ("FAILURE", "FAILED")
    assert result.reason == "Sloppy returned None, not a Status"


@pytest.mark.parametrize(
    "body, shown",
    [
        ("raise ValueError('first line\\nthe last line')", "ValueError: the last line (at crashing.py:5)"),
        ("return self.step()", "RecursionError: maximum recursion depth exceeded"),
        ("raise MemoryError", "MemoryError (at crashing.py:5)"),
        ("import sys; sys.exit(3)", "SystemExit: 3 (at crashing.py:5)"),
    ],
)
def test_a_plugin_that_raises_ends_the_run_failure_with_report_and_log(tmp_path, body, shown):
    import json

    from click.testing import CliRunner

    from thymio_bt.cli import main

    (tmp_path / "crashing.py").write_text(
        "from thymio_bt.behaviours import RobotBehaviour\n"
        "class Crashing(RobotBehaviour):\n"
        "    '''Has a bug.'''\n"
        "    def step(self):\n"
        f"        {body}\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nplugins: [crashing.py]\n"
        "tree:\n  sequence: [{MoveDistance: {distance: 5cm}}, Crashing]\n"
    )
    result = CliRunner().invoke(
        main, ["run", str(mission), "--report", str(tmp_path / "r.json"), "--log", str(tmp_path / "r.jsonl")]
    )
    assert result.exit_code == 1 and "Traceback" not in result.output
    report = json.loads((tmp_path / "r.json").read_text())
    assert (report["status"], report["code"]) == ("FAILURE", "EXCEPTION")
    assert report["reason"].startswith(f"Crashing raised {shown}")
    assert report["failed_path"].endswith("Crashing")
    last = json.loads((tmp_path / "r.jsonl").read_text().splitlines()[-1])
    assert last["kind"] == "end" and last["code"] == "EXCEPTION"


def test_a_missions_plugins_are_listed_documented_and_in_its_schema():
    import json

    from click.testing import CliRunner

    from thymio_bt.cli import main

    mission = ["--mission", f"{ROOT}/examples/spin_until_clear.yaml"]
    assert "SpinUntilClear" in CliRunner().invoke(main, ["behaviours", *mission]).output
    assert "SpinUntilClear" not in CliRunner().invoke(main, ["behaviours"]).output
    doc = CliRunner().invoke(main, ["behaviours", "SpinUntilClear", *mission])
    assert doc.exit_code == 0 and "Parameters:" in doc.output
    schema = json.loads(CliRunner().invoke(main, ["schema", *mission]).stdout)
    assert "SpinUntilClear" in json.dumps(schema["$defs"]["node"])


MARKER_PLUGIN = '''\
from pathlib import Path
from py_trees.common import Status
from thymio_bt.behaviours import RobotBehaviour
Path(__file__).with_name("IMPORTED").write_text("plugin code ran")

class Marker(RobotBehaviour):
    """Succeeds at once."""
    yaml_name = "MarkIt"

    def step(self):
        return Status.SUCCESS
'''


@pytest.mark.parametrize("command", [["validate"], ["tree"], ["tree", "--dot", "-o", "-"], ["tree", "--btcpp", "-"]])
def test_validate_and_tree_read_plugins_without_running_their_code(tmp_path, command):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    (tmp_path / "marker.py").write_text(MARKER_PLUGIN)
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nplugins: [marker.py]\ntree:\n  sequence: [Stop, {MarkIt: {timeout: x}}]\n"
    )
    result = CliRunner().invoke(main, [command[0], str(mission), *command[1:]])
    assert result.exit_code == 0, result.output
    assert "MarkIt" in result.output or command[0] == "validate"
    assert not (tmp_path / "IMPORTED").exists()
    if command == ["validate"]:
        assert "not checked: the parameter values of 1 plugin node, MarkIt (line 5)" in result.output


def test_validate_plugins_imports_them_and_checks_their_parameters(tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    (tmp_path / "marker.py").write_text(MARKER_PLUGIN)
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nplugins: [marker.py]\ntree:\n  sequence: [Stop, {MarkIt: {x: 1}}]\n"
    )
    result = CliRunner().invoke(main, ["validate", "--plugins", str(mission)])
    assert result.exit_code == 2 and "MarkIt has no parameter 'x'" in result.output
    assert (tmp_path / "IMPORTED").exists()


def test_a_plugin_that_is_not_python_is_located_without_running_it(tmp_path):
    from thymio_bt.errors import UserError

    (tmp_path / "broken.py").write_text("class X(RobotBehaviour):\n    def step(self) return 1\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [broken.py]\ntree: Stop\n")
    with pytest.raises(UserError) as err:
        load_mission(mission, run_plugins=False)
    assert "invalid Python" in err.value.problems[0].message and err.value.problems[0].line == 2


SUBCLASS_PLUGIN = '''\
from thymio_bt.behaviours.maze import WallAhead
from thymio_bt.behaviours.motion import Stop

class NearWall(WallAhead):
    """WallAhead under another name."""

class Halt(Stop):
    """Stop, named by its body."""
    yaml_name = "HaltNow"

class FullStop(Halt):
    """A subclass of a plugin's own node."""
'''


@pytest.mark.parametrize("imported", [True, False])
def test_a_plugin_may_subclass_a_builtin_and_its_own_nodes(tmp_path, imported):
    """A subclass is a node of its own name (not its parent's, which would clash with the built-in),
    whether the plugin is imported (run) or only read (validate)."""
    from click.testing import CliRunner

    from thymio_bt.cli import main

    (tmp_path / "sub.py").write_text(SUBCLASS_PLUGIN)
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nplugins: [sub.py]\n"
        "tree:\n  sequence: [{NearWall: {distance: 3cm}}, HaltNow, FullStop, WallAhead]\n"
    )
    result = CliRunner().invoke(main, ["validate", str(mission), *(["--plugins"] if imported else [])])
    assert result.exit_code == 0, result.output
    assert ("not checked" in result.output) is not imported


def test_a_plugin_that_failed_to_import_fails_again_in_the_same_process(tmp_path):
    """The second mission naming a broken plugin gets the same error, not the half-run module."""
    (tmp_path / "broken.py").write_text(
        "from thymio_bt.behaviours import RobotBehaviour\n"
        "class Half(RobotBehaviour):\n    pass\n"
        "raise ValueError('late')\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [broken.py]\ntree: Half\n")
    for _ in range(2):
        with pytest.raises(UserError, match="ValueError: late"):
            load_mission(mission)


def test_a_plugin_whose_parameter_is_called_name_is_refused_at_its_plugins_line(tmp_path):
    """``name:`` labels a node, so a parameter called ``name`` could never be set: say so at once."""
    (tmp_path / "named.py").write_text(
        "from pydantic import Field\n"
        "from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour\n"
        "class GreetParams(BehaviourParams):\n"
        "    name: str = Field('thymio')\n"
        "class Greet(RobotBehaviour):\n"
        "    Params = GreetParams\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [named.py]\ntree:\n  Greet: {name: hello}\n")
    with pytest.raises(UserError) as err:
        load_mission(mission)
    problem = err.value.problems[0]
    assert (problem.line, problem.column) == (3, 11)  # the plugin's place in plugins:
    assert "node 'Greet' has a parameter called 'name'" in problem.message
    assert "'name:' is the node's label" in problem.message


def test_validate_finds_a_plugin_nodes_misspelt_parameter_and_says_what_it_did_not_check(tmp_path):
    """'ok' read as 'run accepts it', and run then failed on the misspelt parameter: the names a
    plugin's Params declares are read from its source (never run); its values are said unchecked."""
    from click.testing import CliRunner

    from thymio_bt.cli import main

    example = Path(__file__).resolve().parents[1] / "examples"
    ran = "\nimport pathlib\npathlib.Path(__file__).with_name('RAN').touch()\n"  # if the plugin's code runs
    (tmp_path / "spin_until_clear.py").write_text((example / "spin_until_clear.py").read_text() + ran)
    text = (example / "spin_until_clear.yaml").read_text().replace("../mazes/arena.yaml", "arena")
    mission = tmp_path / "m.yaml"
    mission.write_text(text.replace("{rate: 90deg/s}", "{rat: 90deg/s}"))
    result = CliRunner().invoke(main, ["validate", str(mission)])
    assert result.exit_code == 2, result.output
    assert f"{mission}:11:24: SpinUntilClear has no parameter 'rat'" in result.output
    assert "did you mean 'rate'?" in result.output
    mission.write_text(text.replace("{rate: 90deg/s}", "{rate: 9 m}"))  # a value: only the import checks it
    result = CliRunner().invoke(main, ["validate", str(mission)])
    assert result.exit_code == 0, result.output
    said = result.output.splitlines()
    assert said[0].startswith(f"ok: {mission} (3 nodes, maze arena); not checked: the parameter values of 1 plugin")
    assert "SpinUntilClear (line 11)" in said[0]
    command = f"thymio-bt validate --plugins {mission}"
    assert said[1] == f"  check them with: {command} (it imports the plugins: runs their code)"
    assert not (tmp_path / "RAN").exists()
    result = CliRunner().invoke(main, ["validate", "--plugins", str(mission)])
    assert result.exit_code == 2 and "expected an angular speed (in rad/s), got a length" in result.output


UNFOLLOWABLE = [
    "class P(BehaviourParams):\n    model_config = ConfigDict(extra='allow')\n    rate: float = 1\n",
    "class P(SomeoneElsesParams):\n    rate: float = 1\n",
    "class P(BehaviourParams):\n    rate: float = Field(1, alias='speed')\n",
    "P = make_params()\n",
]


@pytest.mark.parametrize("params", UNFOLLOWABLE, ids=["extra", "unknown base", "alias", "not a class"])
def test_a_plugin_whose_parameters_cannot_be_read_from_its_source_is_left_unchecked(tmp_path, params):
    from thymio_bt.plan.unrun_plugins import plugin_nodes

    plugin = tmp_path / "p.py"
    plugin.write_text(params + "class Spin(RobotBehaviour):\n    Params = P\n")
    assert plugin_nodes(plugin, {"BehaviourParams": ["timeout"]}) == {"Spin": None}
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: [p.py]\ntree:\n  Spin: {anything: 1}\n")
    assert load_mission(mission, run_plugins=False).tree.behaviour == "Spin"


def test_parameter_names_are_followed_through_the_files_own_bases_and_the_built_ins(tmp_path):
    from thymio_bt.plan.unrun_plugins import plugin_nodes

    plugin = tmp_path / "p.py"
    plugin.write_text(
        "class Base(BehaviourParams):\n    speed: Speed = 0.1\n"
        "class P(Base):\n    rate: float = 1\n    LIMIT: ClassVar[int] = 3\n"
        "class Spin(RobotBehaviour):\n    Params = P\n"
        "class FastSpin(Spin):\n    yaml_name = 'Fast'\n"
        "class Follow(WallFollow):\n    pass\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\nplugins: [p.py]\n"
        "tree:\n  sequence: [{Fast: {rat: 1}}, {Follow: {sid: left}}, {Spin: {speed: 1, rate: 2, timeout: 3}}]\n"
    )
    with pytest.raises(UserError) as err:
        load_mission(mission, run_plugins=False)
    assert [(p.message, p.hint) for p in err.value.problems] == [
        ("Fast has no parameter 'rat'", "did you mean 'rate'?"),
        ("Follow has no parameter 'sid'", "did you mean 'side'?"),
    ]
    assert plugin_nodes(plugin, {"BehaviourParams": ["timeout"]})["Spin"] == ["rate", "speed", "timeout"]


def test_a_hostile_plugins_cycles_and_diamonds_of_params_are_read_once(tmp_path):
    from thymio_bt.plan.unrun_plugins import plugin_nodes

    chain = "".join(f"class P{i}(P{i + 1}, P{i + 1}, P{i + 1}):\n    f{i}: int = 0\n" for i in range(200))
    plugin = tmp_path / "p.py"
    plugin.write_text(
        "class A(B):\n    a: int = 0\nclass B(A):\n    b: int = 0\n"
        f"{chain}class P200(BehaviourParams):\n    last: int = 0\n"
        "class Loop(RobotBehaviour):\n    Params = A\nclass Deep(RobotBehaviour):\n    Params = P0\n"
    )
    found = plugin_nodes(plugin, {"BehaviourParams": ["timeout"]})  # 3**200 paths if not read once each
    assert found["Loop"] is None and found["Deep"] is not None and len(found["Deep"]) == 202
    plugin.write_text(
        "".join(f"class Q{i}(Q{i + 1}):\n    f: int = 0\n" for i in range(5000))
        + "class Q5000(BehaviourParams):\n    pass\nclass Deeper(RobotBehaviour):\n    Params = Q0\n"
    )
    assert plugin_nodes(plugin, {"BehaviourParams": ["timeout"]}) == {"Deeper": None}  # past MAX_BASES
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(100_000)  # as a test runner or a notebook may: the bound is the module's own
    try:
        assert plugin_nodes(plugin, {"BehaviourParams": ["timeout"]}) == {"Deeper": None}
    finally:
        sys.setrecursionlimit(limit)


@pytest.mark.parametrize("ref", ["spin_plugin_by_name.py:Spin", "spin_plugin_by_name:Spin"])
def test_a_named_plugin_class_not_imported_is_known_by_its_yaml_name(tmp_path, monkeypatch, ref):
    """``plugins: [module:Class]`` under validate, tree and lint: the class's ``yaml_name``, as an
    imported one is registered, with its parameters read from the source; never its class name."""
    (tmp_path / "spin_plugin_by_name.py").write_text(
        "import os\nos.abort()\n"
        "class SpinParams(BehaviourParams):\n    rate: float = 1\n"
        "class Spin(RobotBehaviour):\n    yaml_name = 'SpinInPlace'\n    Params = SpinParams\n"
        "class Other(RobotBehaviour):\n    pass\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    mission = tmp_path / "m.yaml"
    mission.write_text(f"maze: arena\nstart: centre\nplugins: ['{ref}']\ntree:\n  SpinInPlace: {{rat: 2}}\n")
    with pytest.raises(UserError) as err:
        load_mission(mission, run_plugins=False)
    assert [(p.message, p.hint) for p in err.value.problems] == [
        ("SpinInPlace has no parameter 'rat'", "did you mean 'rate'?")
    ]
    mission.write_text(f"maze: arena\nstart: centre\nplugins: ['{ref}']\ntree:\n  SpinInPlace: {{rate: 2}}\n")
    registry = load_mission(mission, run_plugins=False).registry
    assert "SpinInPlace" in registry and "Spin" not in registry and "Other" not in registry


def test_a_named_plugin_class_whose_source_cannot_be_read_keeps_its_class_name(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: arena\nstart: centre\nplugins: ['no_such_pkg.nodes:Spin']\ntree:\n  Spin: {any: 1}\n")
    assert load_mission(mission, run_plugins=False).tree.behaviour == "Spin"
