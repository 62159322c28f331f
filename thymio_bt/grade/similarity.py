"""Submissions that are the same tree: equal up to node names, comments, formatting and parameter
values (a copy with its numbers and names changed is still a copy). For the TA only: results.json's
``similar`` and the class page list the groups; nothing is taken off a score for it.

Example::

    >>> from thymio_bt.behaviours.motion import MoveUntilWall
    >>> from thymio_bt.plan.model import NodePlan
    >>> def tree(name, speed):
    ...     leaf = NodePlan("behaviour", f"{name} leaf", f"{name}/leaf", behaviour="MoveUntilWall",
    ...                     params=MoveUntilWall.Params(speed=speed))
    ...     return NodePlan("sequence", name, name, children=[leaf, NodePlan("behaviour", "t", "t", behaviour="Stop")])
    >>> tree_shape(tree("ada", 0.1)) == tree_shape(tree("bob", 0.2))
    True
    >>> similar_groups([("ada", tree_shape(tree("a", 0.1))), ("bob", "other"), ("chen", tree_shape(tree("c", 0.12))),
    ...                 ("eve", None)])
    [['ada', 'chen']]
"""

from __future__ import annotations

import hashlib

from thymio_bt.plan.model import NodePlan


def tree_shape(plan: NodePlan) -> str:
    """A digest of the tree's shape: each node's type and its children's shapes, in order; names,
    parameters, comments and formatting left out."""

    def shape(node: NodePlan) -> str:
        return f"{node.behaviour or node.kind}({','.join(shape(c) for c in node.children)})"

    return hashlib.sha256(shape(plan).encode()).hexdigest()[:16]


def similar_groups(shapes: list[tuple[str, str | None]]) -> list[list[str]]:
    """The groups of two or more students whose trees have the same shape (of each student's name and
    :func:`tree_shape`, None when no tree was read), each group's names in the results' order, the
    groups by their first student."""
    groups: dict[str, list[str]] = {}
    for name, shape in shapes:
        if shape:
            groups.setdefault(shape, []).append(name)
    return [names for names in groups.values() if len(names) > 1]
