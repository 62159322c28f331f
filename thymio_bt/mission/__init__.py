"""Mission YAML → validated plan → py_trees tree; and the behaviour registry."""

from .build import build_tree
from .loader import load_mission
from .plan import Mission, NodePlan
from .registry import Registry, default_registry

__all__ = ["Mission", "NodePlan", "Registry", "build_tree", "default_registry", "load_mission"]
