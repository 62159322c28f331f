"""Ticking a tree without py_trees' generators: the same hooks in the same order, a fraction of the cost.

py_trees' ``tick()`` is a generator at every level: each node a leaf yields passes up through every
ancestor's generator (five or six in a course mission), and every composite and decorator builds a
debug string per tick whether or not anything logs it. Visitors need the yields; a run without them
does not. :func:`tick` gives the tree one tick by calling the nodes' own ``initialise``, ``update``,
``stop`` and ``terminate`` exactly as py_trees' ``tick()`` does, for the node kinds the mission
language builds: py_trees' Sequence and Selector (with or without memory), Parallel (success on all
or on one), any Decorator that keeps
py_trees' tick, our behaviours (:meth:`~thymio_bt.behaviours.base.RobotBehaviour.tick_direct`) and
anything else with a ``tick_direct`` method. Any other node (a plugin's composite, a parallel of
another policy or a decorator with its own tick) is ticked through its generator, so the result never differs:
``tests/test_ticking.py`` runs every mission both ways and compares the reports.

Example::

    >>> from py_trees.behaviours import Running, Success
    >>> root = Sequence("legs", memory=True, children=[Success("first"), Running("second")])
    >>> tick(root)  # like root.tick_once(), without the generators
    >>> root.status, [child.status.name for child in root.children]
    (<Status.RUNNING: 'RUNNING'>, ['SUCCESS', 'RUNNING'])
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import cast

from py_trees.behaviour import Behaviour
from py_trees.common import ParallelPolicy, Status
from py_trees.composites import Parallel, Selector, Sequence
from py_trees.decorators import Decorator

from thymio_bt.behaviours.base import FAILURE, INVALID, RUNNING, SUCCESS

_STATUSES = frozenset(Status)
_SUCCESS_ON_ALL, _SUCCESS_ON_ONE = ParallelPolicy.SuccessOnAll, ParallelPolicy.SuccessOnOne

_Tick = Callable[[Behaviour], None]


class _TickByClass(dict):
    """How each node class is ticked, found on first use: ``TICK_OF[node.__class__](node)`` is one
    dict lookup and no Python call (composites tick their children that way: a call less per child)."""

    def __missing__(self, kind: type[Behaviour]) -> _Tick:
        # the table dispatches by class: each function below only ever gets nodes of its class,
        # which the type of a table of callables cannot say (hence the casts)
        how: _Tick = _generator
        direct = getattr(kind, "tick_direct", None)
        if direct is not None:
            how = direct
        elif kind.tick is Sequence.tick:
            how = cast(_Tick, _sequence)
        elif kind.tick is Selector.tick:
            how = cast(_Tick, _selector)
        elif kind.tick is Parallel.tick:
            how = cast(_Tick, _parallel)
        elif issubclass(kind, Decorator) and kind.tick is Decorator.tick:
            how = cast(_Tick, _decorator)
        self[kind] = how
        return how


#: the direct tick of each node class, or its generator when it has one of its own:
#: ``TICK_OF[node.__class__](node)`` is :func:`tick` without its call (for the loops that tick a
#: child on every tick: the runner's, the composites', RepeatUntil's)
TICK_OF: dict[type, _Tick] = _TickByClass()


def tick(node: Behaviour) -> None:
    """Give ``node`` (and its subtree) one tick, as ``node.tick_once()`` would."""
    TICK_OF[node.__class__](node)


def _generator(node: Behaviour) -> None:
    """py_trees' own tick, through its generator (for the node kinds this module does not know)."""
    for _ in node.tick():
        pass


def _invalidate(children: Iterable[Behaviour]) -> None:
    """Stop (reset to INVALID) each of ``children`` that is not already, as py_trees' composites do."""
    for child in children:
        if child.status is not INVALID:
            child.stop(INVALID)


def _sequence(seq: Sequence) -> None:
    """py_trees' ``Sequence.tick``: resume at the running child (memory) or start over."""
    children = seq.children
    index = 0
    if seq.status is not RUNNING:
        seq.current_child = children[0] if children else None
        _invalidate(children)
        seq.initialise()
    elif seq.memory and seq.current_child is not None:
        index = children.index(seq.current_child)
    else:
        seq.current_child = children[0] if children else None
    if not children:
        seq.current_child = None
        seq.stop(SUCCESS)
        return
    last = len(children) - 1
    while index <= last:
        child = children[index]
        TICK_OF[child.__class__](child)
        status = child.status
        if status is not SUCCESS:
            if not seq.memory:  # invalidate the rest: no dangling runners
                _invalidate(children[index + 1 :])
            if status is not RUNNING:
                seq.stop(status)
            else:
                seq.status = status
            return
        if index < last:
            seq.current_child = children[index + 1]
        index += 1
    seq.stop(SUCCESS)


def _selector(sel: Selector) -> None:
    """py_trees' ``Selector.tick``: the first child that does not fail wins; a change of winner
    invalidates the lower priorities."""
    children = sel.children
    if sel.status is not RUNNING:
        sel.current_child = children[0] if children else None
        sel.initialise()
    if not children:
        sel.current_child = None
        sel.stop(FAILURE)
        return
    if sel.memory:
        assert sel.current_child is not None  # set above when it started, kept while it runs
        index = children.index(sel.current_child)
        _invalidate(children[:index])
    else:
        index = 0
    previous = sel.current_child
    for child in children[index:]:
        TICK_OF[child.__class__](child)
        status = child.status
        if status is RUNNING or status is SUCCESS:
            sel.current_child = child
            if previous is None or previous != child:
                passed = False
                for other in children:
                    if passed and other.status is not INVALID:
                        other.stop(INVALID)
                    passed = True if other == child else passed
            if status is SUCCESS:
                sel.stop(status)
            else:
                sel.status = status
            return
    sel.stop(FAILURE)
    sel.current_child = children[-1]


def _parallel(par: Parallel) -> None:
    """py_trees' ``Parallel.tick`` with the policies the mission language builds (success on all,
    success on one); another policy goes through the generator."""
    policy = par.policy
    if policy.__class__ is not _SUCCESS_ON_ALL and policy.__class__ is not _SUCCESS_ON_ONE:
        _generator(par)  # SuccessOnSelected (whose configuration its tick validates) or another
        return
    children = par.children
    if par.status is not RUNNING:
        _invalidate(children)
        par.current_child = None
        par.initialise()
    if not children:
        par.current_child = None
        par.stop(SUCCESS)
        return
    synchronise = policy.synchronise
    for child in children:
        if synchronise and child.status is SUCCESS:
            continue
        TICK_OF[child.__class__](child)
    new_status = _parallel_status(par, policy.__class__ is _SUCCESS_ON_ALL)
    if new_status is not RUNNING:
        par.stop(new_status)
    par.status = new_status


def _parallel_status(par: Parallel, on_all: bool) -> Status:
    """What the children's statuses make of the parallel (any failure fails it; success on all or
    on one), setting ``current_child`` as py_trees does."""
    children = par.children
    par.current_child = children[-1]
    succeeded = 0
    for child in children:
        status = child.status
        if status is FAILURE:
            par.current_child = child
            return FAILURE
        if status is SUCCESS:
            succeeded += 1
    if on_all:
        if succeeded == len(children):
            par.current_child = children[-1]
            return SUCCESS
        return RUNNING
    for child in reversed(children):
        if child.status is SUCCESS:
            par.current_child = child
            return SUCCESS
    return RUNNING


def _decorator(dec: Decorator) -> None:
    """py_trees' ``Decorator.tick``: the child first, then the decorator's own update."""
    if dec.status is not RUNNING:
        dec.initialise()
    tick(dec.decorated)
    new_status = dec.update()
    if new_status not in _STATUSES:
        new_status = INVALID
    if new_status is not RUNNING:
        dec.stop(new_status)
    dec.status = new_status
