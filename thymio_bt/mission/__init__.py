"""Mission YAML → validated plan → py_trees tree; and the behaviour registry.

Example::

    >>> mission = load_mission("square")                    # a shipped mission, by name
    >>> mission.tree.kind, mission.tree.params, [child.behaviour for child in mission.tree.children[0].children]
    ('repeat', RepeatParams(times=4), ['MoveDistance', 'TurnAngle'])
"""

from thymio_bt.mission.build import build_tree
from thymio_bt.mission.loader import load_mission
from thymio_bt.plan.model import Mission, NodePlan
from thymio_bt.plan.registry import Registry, default_registry

__all__ = ["Mission", "NodePlan", "Registry", "build_tree", "default_registry", "load_mission"]
