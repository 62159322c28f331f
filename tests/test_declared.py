"""One home for each fact (issue 45): one angle wrap, and nothing probed with getattr that a class
can declare (``proximity_raw``, ``unrun_plugin``, ``bt_sync``, ``keep_moving``, ``failure``, ``mark``,
then ``params``, ``tip_path``, ``plugin_files``, ``detail``, ``marks``, ``Params``, ``execute_tick``):
``getattr(obj, "name")`` and ``hasattr`` only where ``obj`` is not ours to declare, each with its
reason in :data:`FOREIGN`."""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

import thymio_bt
from thymio_bt.backends.sim import Simulation
from thymio_bt.behaviours.base import ConditionBehaviour, RobotBehaviour, UnrunPlugin, node_path
from thymio_bt.behaviours.flow.node import node_kind
from thymio_bt.behaviours.motion import MoveDistance, MoveUntilWall, Stop, TurnAngle
from thymio_bt.mission.loader import load_mission
from thymio_bt.plan.model import NodePlan
from thymio_bt.plan.registry import default_registry
from thymio_bt.plan.unrun_plugins import stand_in
from thymio_bt.robot.calibrate import START, arena, calibrate
from thymio_bt.robot.interface import Robot
from thymio_bt.robot.model import COURSE
from thymio_bt.run.runner import Run

PACKAGE = Path(thymio_bt.__file__).parent
SOURCES = {p.relative_to(PACKAGE).as_posix(): p.read_text(encoding="utf-8") for p in PACKAGE.rglob("*.py")}


def test_the_angle_wrap_is_written_once():
    inlined = re.compile(
        r"%\s*(\(\s*2(\.0)?\s*\*\s*math\.pi\s*\)|_?TAU\b|math\.tau\b)|while\s+[\w.]+\s*[<>]=?\s*-?math\.pi"
    )
    places = [path for path, text in SOURCES.items() for _ in inlined.finditer(text)]
    assert places == ["geometry.py"]  # wrap_angle itself


#: (module, attribute) probed -> why it cannot be declared
FOREIGN = {
    ("backends.real.aseba", "failed"): "thymiodirect's connection objects",
    ("backends.real.aseba", "var_received"): "thymiodirect's remote node",
    ("backends.ros2.messages", "range"): "a ROS message of either sensor type",
    ("behaviours.flow.ticking", "tick_direct"): "the fast-tick protocol any node class may offer, a plugin's too",
    ("cli.app", "exit_code"): "click's exceptions",
    ("inputs.validation", "__args__"): "typing's annotations",
    ("inputs.yamlio", "anchor"): "PyYAML's events",
    ("analysis.node_docs", "__name__"): "typing's annotations",
    ("analysis.node_docs", "UnionType"): "the types module of the running Python",
    ("run.coverage", "current_child"): "py_trees' composites, and plugins' duck-typed ones",
    ("run.coverage", "_coverage"): "set on any node by the coverage counting itself, py_trees' included",
    ("run.interrupts", "pthread_kill"): "the signal module of the running platform",
    ("run.leftovers", "__spec__"): "the __main__ module",
    ("run.leftovers", "name"): "the __main__ module's spec, if any",
    ("viz.terminal", "isatty"): "any output stream",
}


def probes() -> set[tuple[str, str]]:
    """(module, attribute) of every getattr/hasattr with a literal attribute name in the package."""
    found = set()
    for path in PACKAGE.rglob("*.py"):
        module = path.relative_to(PACKAGE).with_suffix("").as_posix().replace("/", ".")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id in ("getattr", "hasattr")
                and len(node.args) >= 2
                and isinstance(node.args[1], ast.Constant)
            ):
                found.add((module, node.args[1].value))
    return found


def test_every_probed_attribute_is_one_we_cannot_declare():
    unexplained = probes() - set(FOREIGN)
    assert not unexplained, f"declare these and read them as attributes (or say why not in FOREIGN): {unexplained}"


def test_the_reasons_are_for_probes_that_still_exist():
    assert set(FOREIGN) <= probes(), f"no longer probed: {set(FOREIGN) - probes()}"


def test_every_robot_declares_its_raw_readings():
    assert Robot.raw_readings is False
    metres = Simulation(arena(), spawn=START, config=None)  # metres by default: no integers to read
    assert metres.raw_readings is False and metres.proximity_raw() is None


def test_calibrate_refuses_a_robot_without_raw_readings():
    """A metres simulation is refused before the approach (it was let through, then failed asking
    whether the robot faced the wall)."""
    with pytest.raises(ValueError, match="gives no raw readings"):
        calibrate(Simulation(arena(), spawn=START), COURSE, arena(), say=lambda text: None)


def test_node_kinds_declare_what_tools_used_to_probe():
    assert issubclass(stand_in("Spin"), UnrunPlugin) and not issubclass(MoveDistance, UnrunPlugin)
    assert ConditionBehaviour.bt_sync and not RobotBehaviour.bt_sync
    for motion in (MoveUntilWall, MoveDistance, TurnAngle):
        params = motion.Params.model_validate({"keep_moving": True, **_required(motion)})
        node = motion.__new__(motion)
        node.params = params
        assert node.keeps_moving()
    assert not Stop.keeps_moving(Stop.__new__(Stop))


def test_the_analyses_name_no_leaf_the_facts_are_on_the_classes():
    """The lint's rules read what a leaf is and does from its class (``condition``, ``clear_ahead``,
    ``drives_forward``...), not from tables of names: no string in ``analysis/`` (docstrings aside)
    names a behaviour of the package."""
    names = {name for name, _ in default_registry().behaviours()}
    named = []
    for path in (PACKAGE / "analysis").glob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docs = {
            id(node.body[0].value)
            for node in ast.walk(tree)
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef)
            and node.body
            and isinstance(node.body[0], ast.Expr)
        }
        named += [
            (path.name, node.value)
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and node.value in names and id(node) not in docs
        ]
    assert not named, named


def test_built_in_leaves_declare_their_way_ahead_facts():
    from thymio_bt.behaviours.maze import SideOpen, WallAhead
    from thymio_bt.behaviours.navigation import GoToPose, ObstacleAhead
    from thymio_bt.btcpp.runtime.scripted import Script, ScriptCondition

    assert ScriptCondition.condition and WallAhead.condition and not Script.condition
    assert WallAhead.clear_ahead(WallAhead.Params(distance=0.08)) == 0.08 and SideOpen.clear_ahead(None) is None
    assert ObstacleAhead.clear_ahead(ObstacleAhead.Params()) == 0.03
    assert MoveDistance.drives_forward(MoveDistance.Params(distance=0.3)) == 0.3
    assert GoToPose.drives_forward(None) == math.inf and TurnAngle.drives_forward(None) == 0


def test_no_class_of_the_package_is_a_bare_node():
    """``Node`` meant an Aseba device, a node class and an rclpy node: the devices are ``AsebaDevice``s
    (``TdmDevice``, ``AsebaNode``), rclpy's is a ``SpunRosNode``'s ``ros_node``."""
    from thymio_bt.backends.real import AsebaDevice, TdmDevice
    from thymio_bt.backends.real.aseba import AsebaNode

    assert issubclass(TdmDevice, AsebaDevice) and issubclass(AsebaNode, AsebaDevice)
    classes = {
        node.name: path
        for path, text in SOURCES.items()
        for node in ast.walk(ast.parse(text))
        if isinstance(node, ast.ClassDef)
    }
    assert "Node" not in classes and "SpunNode" not in classes and classes["SpunRosNode"] == "backends/ros2/node.py"


def test_no_public_name_list_is_a_copy_of_another():
    """A package that re-exports a module's names takes its ``__all__`` (``robot`` once copied the
    interface's, name for name)."""
    lists: dict[tuple[str, ...], list[str]] = {}
    for path, text in SOURCES.items():
        for node in ast.parse(text).body:
            named = isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in node.targets)
            value = node.value if isinstance(node, ast.Assign) else None
            if named and isinstance(value, ast.List) and all(isinstance(e, ast.Constant) for e in value.elts):
                lists.setdefault(tuple(sorted(e.value for e in value.elts)), []).append(path)
    assert [paths for paths in lists.values() if len(paths) > 1] == []


def _required(motion: type[RobotBehaviour]) -> dict[str, float]:
    return {"distance": 0.1} if motion is MoveDistance else {"angle": 1.0} if motion is TurnAngle else {}


def test_the_sensor_model_names_are_declared_once():
    """The simulator's sensor models and the robot models' names for them live in robot/model.py
    alone: the mission settings had their own tuple and their own ``rays`` -> ``metres`` table."""
    from typing import get_args

    from thymio_bt.mission import load_mission
    from thymio_bt.plan.model import Mission
    from thymio_bt.robot.model import ROBOTS, SIM_SENSOR_MODEL, SIM_SENSOR_MODELS, SimSensorModel

    spelt = re.compile(r"\"metres\",\s*\"raw\",\s*\"cone\"")
    assert [path for path, text in SOURCES.items() for _ in spelt.finditer(text)] == ["robot/model.py"]
    assert get_args(SimSensorModel) == SIM_SENSOR_MODELS == tuple(SIM_SENSOR_MODEL.values())
    for name, robot in ROBOTS.items():  # a mission's default is its robot's own, in the simulator's name
        assert load_mission("square", {"robot": name}).sensor_model == SIM_SENSOR_MODEL[robot.sensor_model]
    for written in (*SIM_SENSOR_MODEL, *SIM_SENSOR_MODELS):
        assert load_mission("square", {"sensor_model": written}).sensor_model in SIM_SENSOR_MODELS
    hints = Mission.__annotations__  # named, not Any: mypy checks their readers
    assert (hints["sensor_model"], hints["registry"], hints["expect"]) == (
        "SimSensorModel",
        "Registry",
        "Expect | None",
    )


def test_node_status_encodings_are_derived_from_one_declaration():
    """A node status's log letter, BT.CPP/Groot2 number and wire code were five tables in five
    modules; now enums.py declares them and the others derive theirs, each format unchanged."""
    from py_trees.common import Status

    from thymio_bt.btcpp import btlog, groot2
    from thymio_bt.enums import NODE_STATUSES, STATUS_LETTER
    from thymio_bt.grade import wire
    from thymio_bt.logs import entries
    from thymio_bt.run import divergence

    assert STATUS_LETTER == {"SUCCESS": "S", "FAILURE": "F", "RUNNING": "R", "INVALID": "-"}  # the logs' letters
    assert set(NODE_STATUSES) == {s.name for s in Status} and entries.STATUS_LETTER is STATUS_LETTER
    assert groot2._STATUS == {"INVALID": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3}  # BT.CPP's NodeStatus
    assert wire.STATUSES == NODE_STATUSES and btlog.LETTER == {0: "-", 1: "R", 2: "S", 3: "F", 4: "-"}
    assert btlog.ENDED == {"S": "SUCCESS", "F": "FAILURE"}
    assert divergence.STATUS_WORD == {"S": "SUCCESS", "F": "FAILURE", "R": "RUNNING", "-": "INVALID"}
    table = re.compile(r"\"(SUCCESS|FAILURE|RUNNING|INVALID)\":\s*(\"[SFR-]\"|\d)|\"[SFR-]\":\s*\"(SUCCESS|FAILURE)")
    assert [path for path, text in SOURCES.items() if table.search(text)] == []


def test_no_angle_is_wrapped_through_atan2():
    """``atan2(sin(a), cos(a))`` was a third wrap with a third range ((-pi, pi]); the Playground's
    truth now has the simulator's range (``wrap_angle``), a mirrored spawn the range of a start
    pose as written (``math.remainder``, exact, which each such place says why it needs)."""
    atan2_wrap = re.compile(r"atan2\(\s*math\.sin\((?P<a>[^()]*(\([^()]*\))?[^()]*)\),\s*math\.cos\((?P=a)\)\)")
    assert [path for path, text in SOURCES.items() if atan2_wrap.search(text)] == []
    for path, text in SOURCES.items():
        lines = text.splitlines()
        for number, line in enumerate(lines):
            if re.search(r"math\.remainder\([^\n]*math\.tau\)", line):
                said = "\n".join(lines[max(0, number - 3) : number + 1])
                assert "not wrap_angle" in said, f"{path}:{number + 1}: a wrap that does not say why"


def test_what_other_rooms_import_from_the_behaviours_base_is_declared_public():
    """The runner, the recording and the grader import ``snapshot``, ``node_path``, ``describe``,
    ``is_fault`` and ``EventLog`` from behaviours/base.py: its ``__all__`` must say so."""
    from thymio_bt.behaviours import base

    imported = {
        (path, alias.name)
        for path, text in SOURCES.items()
        for node in ast.walk(ast.parse(text))
        if isinstance(node, ast.ImportFrom) and node.module == "thymio_bt.behaviours.base"
        for alias in node.names
    }
    assert {(path, name) for path, name in imported if name not in base.__all__} == set()


def _planned_kinds(plan: NodePlan, parent: str = "") -> Iterator[tuple[str, str]]:
    """(path, kind) of every node of a plan, as the built tree's nodes should be named."""
    path = f"{parent}/{plan.name}" if parent else plan.name
    yield path, plan.behaviour if plan.kind == "behaviour" else plan.kind
    for child in plan.children:
        yield from _planned_kinds(child, path)


#: a mission of BT.CPP 4's built-ins (their kinds' classes are made at import, with a ``make`` of their own)
BTCPP_MISSION = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <ThymioMission maze="{maze}" start="centre" time_limit="20"/>
  <BehaviorTree ID="Main">
    <Sequence>
      <Repeat num_cycles="2"><MoveDistance distance="0.05"/></Repeat>
      <Timeout msec="1500"><Wait seconds="5"/></Timeout>
      <Fallback><AlwaysFailure/><ForceSuccess><Script code="x := 1"/></ForceSuccess></Fallback>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.mark.parametrize(
    "path", [*sorted((PACKAGE / "data" / "missions").glob("*.yaml")), "btcpp.xml"], ids=lambda p: Path(p).stem
)
def test_every_node_of_a_built_mission_has_its_kind_declared(path, tmp_path):
    if path == "btcpp.xml":
        path = tmp_path / path
        path.write_text(BTCPP_MISSION.format(maze=PACKAGE / "data" / "mazes" / "arena.yaml"))
    mission = load_mission(path)
    root = Run(mission).root
    built: dict[str, set[str]] = {}
    for node in root.iterate():
        built.setdefault(node_path(node), set()).add(node_kind(node))
    planned = list(_planned_kinds(mission.tree))
    assert [(p, k) for p, k in planned if k not in built.get(p, set())] == []
    # nothing tagged on py_trees' nodes behind mypy's back: the kind is declared, not probed
    assert [node_path(n) for n in root.iterate() if "yaml_name" in vars(n)] == []


#: the shared types' homes, and the modules that re-export them as public API (their only other source)
HOMES = {
    "Pose": ("thymio_bt.geometry", {"thymio_bt.robot.interface", "thymio_bt.robot"}),
    "new_pose": ("thymio_bt.geometry", {"thymio_bt.robot.interface", "thymio_bt.robot"}),
    "wrap_angle": ("thymio_bt.geometry", {"thymio_bt.robot.interface", "thymio_bt.robot"}),
    "FailureCode": ("thymio_bt.enums", {"thymio_bt.behaviours.base", "thymio_bt.behaviours"}),
    "Mission": ("thymio_bt.plan.model", {"thymio_bt.mission"}),
    "NodePlan": ("thymio_bt.plan.model", {"thymio_bt.mission"}),
}


def test_the_package_imports_each_shared_type_from_its_home():
    """``Pose`` came through robot.interface in 33 modules and through geometry in 3, ``FailureCode``
    through behaviours.base, ``Mission`` through the loader's package: one home each, inside the
    package; the re-exports are for users (and for the re-exporting modules themselves)."""
    elsewhere = []
    for path in sorted(PACKAGE.rglob("*.py")):
        name = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")
        if name == "thymio_bt._moved":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                for alias in node.names:
                    home, exporters = HOMES.get(alias.name, (node.module, set()))
                    if node.module != home and node.module in exporters and name not in exporters:
                        elsewhere.append(f"{name}:{node.lineno} {alias.name} from {node.module}")
    assert elsewhere == []
