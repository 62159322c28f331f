"""Mission YAML → validated plan → py_trees tree; and the behaviour registry."""

from thymio_bt.mission.build import build_tree
from thymio_bt.mission.loader import load_mission
from thymio_bt.mission.plan import Mission, NodePlan
from thymio_bt.mission.registry import Registry, default_registry

__all__ = ["Mission", "NodePlan", "Registry", "build_tree", "default_registry", "load_mission"]
