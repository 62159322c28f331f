"""The built-in nodes known by name before their modules are imported (``plan/builtin_nodes.py``):
the table holds every node class the packages define, and the registry imports a family only when
a node of it is looked up, so a run imports its own nodes and no others."""

import importlib
import inspect
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import thymio_bt.behaviours
import thymio_bt.btcpp.runtime
from thymio_bt.behaviours.base import UnrunPlugin
from thymio_bt.errors import UserError
from thymio_bt.mission import default_registry, load_mission
from thymio_bt.plan.builtin_nodes import BUILTIN_NODES
from thymio_bt.plan.registry import Registry, is_node

ROOT = Path(__file__).resolve().parents[1]

#: node classes meant to be derived from, never named in a mission (private ones, ``_X``, too)
BASES = {
    "RobotBehaviour",
    "ConditionBehaviour",
    "ControlNode",
    "UnrunPlugin",
    "Motion",
    "OnGrid",
    "Sensing",
    "BtControl",
    "BtLeaf",
}


def _defined_node_classes() -> dict[str, str]:
    """Every node class the node packages define (a module's class, or one of a tuple of generated
    ones), imported here, but the bases: YAML name -> ``"module:attr"``."""
    classes: dict[type, str] = {}  # a class where it is a module's attribute, else its tuple
    for package in (thymio_bt.behaviours, thymio_bt.btcpp.runtime):
        for info in pkgutil.walk_packages(package.__path__, f"{package.__name__}."):
            module = importlib.import_module(info.name)
            for attr, value in sorted(vars(module).items(), key=lambda item: isinstance(item[1], tuple)):
                for cls in value if isinstance(value, tuple) else (value,):
                    if inspect.isclass(cls) and is_node(cls) and cls.__module__ == module.__name__:
                        classes.setdefault(cls, f"{module.__name__}:{attr}")
    return {
        cls.yaml_name or cls.__name__: where
        for cls, where in classes.items()
        if cls.__name__ not in BASES and not cls.__name__.startswith("_")
    }


def test_the_table_names_every_node_class_where_it_is():
    assert _defined_node_classes() == BUILTIN_NODES


def test_the_default_registry_has_every_built_in_node_in_the_table_order():
    registry = default_registry()
    assert [name for name in registry if name in BUILTIN_NODES] == list(BUILTIN_NODES)
    for name in BUILTIN_NODES:
        assert (registry[name].yaml_name or registry[name].__name__) == name


def test_a_lazy_node_is_known_by_name_and_imported_when_looked_up():
    registry = Registry(lazy={"Ghost": "thymio_bt_no_such_module:Ghost", "Stop": "thymio_bt.behaviours.motion:Stop"})
    assert "Ghost" in registry and list(registry) == ["Ghost", "Stop"]  # nothing imported to say so
    assert registry["Stop"].__module__ == "thymio_bt.behaviours.motion"
    with pytest.raises(ModuleNotFoundError):
        registry.get("Ghost")


def test_a_table_row_that_says_otherwise_than_the_class_is_refused():
    registry = Registry(lazy={"Halt": "thymio_bt.behaviours.motion:Stop"})
    with pytest.raises(LookupError, match="no node called 'Halt'"):
        registry.get("Halt")


def test_a_plugin_named_as_a_built_in_not_yet_imported_is_still_refused():
    from thymio_bt.behaviours.motion import Stop

    class Spin(Stop):
        yaml_name = "Wait"

    registry = Registry(lazy={"Wait": "thymio_bt.behaviours.motion:Wait"})
    with pytest.raises(ValueError, match="two nodes are named 'Wait'"):
        registry.register(Spin)


def test_a_misspelt_node_is_hinted_among_the_nodes_not_imported(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("name: m\nmaze: arena\nstart: [0.45, 0.45, 0]\ntree:\n  MapWall: {}\n")
    with pytest.raises(UserError, match="unknown node type 'MapWall'.*did you mean 'MapWalls'"):
        load_mission(mission, registry=Registry(lazy=BUILTIN_NODES))


def test_a_run_imports_only_the_families_its_mission_names(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "name: m\nmaze: arena\nstart: [0.45, 0.45, 0]\ntree:\n  sequence: [Wait: {seconds: 0.1}, MapWalls: {}]\n"
    )
    code = (
        "import sys\nfrom thymio_bt.mission import load_mission\n"
        f"load_mission({str(mission)!r})\n"
        "print(sorted(m for m in sys.modules if m.startswith(('thymio_bt.behaviours.', 'thymio_bt.btcpp.'))))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    loaded = eval(done.stdout)
    assert {"thymio_bt.behaviours.motion", "thymio_bt.behaviours.mapping", "thymio_bt.behaviours.flow.composites"} <= {
        *loaded
    }
    assert not {"thymio_bt.behaviours.navigation", "thymio_bt.behaviours.places", "thymio_bt.btcpp.runtime.control"} & {
        *loaded
    }


def test_the_package_still_hands_out_every_behaviour_class_it_lists():
    names = [n for n in thymio_bt.behaviours.__all__ if n in BUILTIN_NODES]
    assert sorted(names) == sorted(
        n for n, where in BUILTIN_NODES.items() if where.startswith("thymio_bt.behaviours.") and ".flow." not in where
    )
    for name in names:
        assert getattr(thymio_bt.behaviours, name) is default_registry()[name]
    with pytest.raises(AttributeError):
        _ = thymio_bt.behaviours.NoSuchBehaviour
    assert not issubclass(default_registry()["Stop"], UnrunPlugin)


def test_import_all_hands_out_every_node_imported():
    registry = Registry(lazy={"Stop": "thymio_bt.behaviours.motion:Stop", "MapWalls": BUILTIN_NODES["MapWalls"]})
    registry.import_all()
    assert all(isinstance(value, type) for value in registry._classes.values())


@pytest.mark.parametrize("module", ["thymio_bt.grade.sandbox", "thymio_bt.grade.grader"])
def test_the_processes_that_fork_students_runs_import_every_family_first(tmp_path, module):
    """The grader and its sandboxes' zygote fork a child per student, whose mission may name any node:
    each family is imported before the fork (as when the registry imported all), not once per child."""
    code = (
        f"import sys\nimport {module} as m\nm._warm()\n"
        "print(all(m in sys.modules for m in ('thymio_bt.behaviours.mapping', 'thymio_bt.btcpp.runtime.control')))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "True"
