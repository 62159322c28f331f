"""BT.CPP 4's nodes that read and write the blackboard with its script language
(:mod:`thymio_bt.btcpp.runtime.script`): ``Script``, ``ScriptCondition``, ``Precondition``,
``SetBlackboard``, ``UnsetBlackboard``, ``Switch2``..``Switch6``, and the pre/post-condition
attributes (``_skipIf``, ``_successIf``, ``_failureIf``, ``_while``, ``_onSuccess``,
``_onFailure``, ``_onHalted``, ``_post``) as a :class:`Conditioned` node around the node they are on.
The blackboard is the run's (py_trees'): ``x`` in a script is ``bb:x`` in a mission.

Example::

    >>> from thymio_bt.behaviours.flow.ticking import tick
    >>> from py_trees.blackboard import Blackboard
    >>> from types import SimpleNamespace
    >>> robot = SimpleNamespace(exists=lambda: False)
    >>> ctx = SimpleNamespace(robot=robot, now=lambda: 0.0, collision_count=lambda: 0)
    >>> script = Script("count", Script.Params(code="n := 41; n += 1"), ctx)
    >>> tick(script); script.status, Blackboard.storage["/n"]
    (<Status.SUCCESS: 'SUCCESS'>, 42)
    >>> check = ScriptCondition("check", Script.Params(code="n == 42"), ctx)
    >>> tick(check); check.status
    <Status.SUCCESS: 'SUCCESS'>
    >>> Blackboard.storage.clear()
"""

from __future__ import annotations

import re
from collections.abc import Iterator, MutableMapping
from typing import Annotated, Any, ClassVar

from py_trees.behaviour import Behaviour
from py_trees.blackboard import Blackboard
from py_trees.common import Status
from pydantic import AfterValidator, Field

from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour
from thymio_bt.behaviours.flow.node import refuse
from thymio_bt.behaviours.flow.primitives import SimTimer
from thymio_bt.btcpp.runtime import decorators as bd
from thymio_bt.btcpp.runtime import nodes as bn
from thymio_bt.btcpp.runtime.script import Script as Code_
from thymio_bt.btcpp.runtime.script import ScriptError, parse
from thymio_bt.btcpp.runtime.values import truth
from thymio_bt.inputs.fields import BlackboardKey, Entry, ScriptText


class RunBoard(MutableMapping[str, Any]):
    """The run's blackboard (py_trees' storage) as the mapping scripts read and write: ``x`` is ``/x``."""

    def __getitem__(self, key: str) -> Any:
        return Blackboard.storage["/" + key.lstrip("/")]

    def __setitem__(self, key: str, value: Any) -> None:
        Blackboard.storage["/" + key.lstrip("/")] = value

    def __delitem__(self, key: str) -> None:
        del Blackboard.storage["/" + key.lstrip("/")]

    def __iter__(self) -> Iterator[str]:
        return (key.lstrip("/") for key in Blackboard.storage)

    def __len__(self) -> int:
        return len(Blackboard.storage)


BOARD = RunBoard()


def run_script(script: Code_, where: str) -> Any:
    """Run ``script`` on the run's blackboard; its failure names the node (the run stops there)."""
    try:
        return script(BOARD)
    except ScriptError as exc:
        raise ScriptError(f"{where}: {exc}") from None


def _code(text: Any) -> Any:
    """A script parameter or port, parsed when the mission is read (its error is the node's, with
    file:line); None stays None (a pre/post-condition not given)."""
    if text is None:
        return None
    try:
        parse(str(text))
    except ScriptError as exc:
        raise refuse(f"invalid script '{text}': {exc}", "BT.CPP's script language: see docs/btcpp.md") from None
    return str(text)


Code = Annotated[str, AfterValidator(_code), ScriptText()]
OptionalCode = Annotated[str | None, AfterValidator(_code), ScriptText()]


class BtLeaf(RobotBehaviour):
    """A BT.CPP built-in leaf: no robot, no events; ``bt_sync``: ticked again even once completed.

    Its BT.CPP ID is its class name, its YAML name that ID in snake case after ``bt_``
    (``ScriptCondition``: ``bt_script_condition``).
    """

    btcpp_id: ClassVar[str] = ""
    bt_sync: ClassVar[bool] = True
    needs_robot = False
    emits_events = False
    fails_on_collision = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Name the leaf after BT.CPP's node."""
        cls.btcpp_id = cls.__name__
        cls.yaml_name = "bt_" + re.sub(r"(?<!^)(?=[A-Z])", "_", cls.__name__).lower()
        super().__init_subclass__(**kwargs)


class CodeParams(BehaviourParams):
    """A script."""

    code: Code = Field(description="the script (BT.CPP's script language)")


class Script(BtLeaf):
    """BT.CPP's ``Script``: run ``code`` on the blackboard, SUCCESS."""

    Params = CodeParams
    always = "S"

    def prepare(self) -> None:
        """Parse the script once."""
        self.script = parse(self.params.code)

    def step(self) -> Status:
        """Run the script."""
        run_script(self.script, self.name)
        return Status.SUCCESS


class ScriptCondition(Script):
    """BT.CPP's ``ScriptCondition``: SUCCESS if ``code`` is true, else FAILURE."""

    always = ""  # true or false
    condition = True

    def step(self) -> Status:
        """The script's truth; the feedback (a failure's reason) says which script and what it gave."""
        value = run_script(self.script, self.name)
        holds = truth(value)
        self.say("'{}' is {} (it gives {!r})", self.params.code, "true" if holds else "false", value)
        return Status.SUCCESS if holds else Status.FAILURE


class SetParams(BehaviourParams):
    """BT.CPP's SetBlackboard ports."""

    value: str = Field(description="the text written, or {key}: that entry's value")
    output_key: BlackboardKey = Field(description="the entry written")


class SetBlackboard(BtLeaf):
    """BT.CPP's ``SetBlackboard``: ``output_key`` gets ``value`` (``{key}``: a copy of that entry)."""

    Params = SetParams
    always = "S"

    def step(self) -> Status:
        """Write the entry."""
        text, key = self.params.value.strip(), self.params.output_key.strip("{}")
        BOARD[key] = BOARD[text[1:-1]] if text.startswith("{") and text.endswith("}") else self.params.value
        return Status.SUCCESS


class KeyParams(BehaviourParams):
    """A blackboard entry."""

    key: Annotated[str, Entry("removed")] = Field(description="the entry")


class UnsetBlackboard(BtLeaf):
    """BT.CPP's ``UnsetBlackboard``: remove the entry ``key`` (SUCCESS even if there was none)."""

    Params = KeyParams
    always = "S"

    def step(self) -> Status:
        """Remove the entry."""
        BOARD.pop(self.params.key.strip("{}"), None)
        return Status.SUCCESS


class AlwaysSuccess(BtLeaf):
    """BT.CPP's ``AlwaysSuccess``."""

    always = "S"

    def step(self) -> Status:
        """SUCCESS."""
        return Status.SUCCESS


class AlwaysFailure(BtLeaf):
    """BT.CPP's ``AlwaysFailure``."""

    always = "F"

    def step(self) -> Status:
        """FAILURE."""
        return Status.FAILURE


class MsecParams(BehaviourParams):
    """A time in milliseconds of simulated time."""

    msec: int = Field(ge=0, description="milliseconds of simulated time")


class Sleep(BtLeaf):
    """BT.CPP's ``Sleep``: RUNNING for ``msec`` milliseconds of simulated time, then SUCCESS."""

    bt_sync = False
    Params = MsecParams

    def start(self) -> None:
        """The wait starts now (``msec`` as resolved: it may come from the blackboard)."""
        self.timer = SimTimer(self.params.msec / 1000.0, self.ctx.now)
        self.timer.start()

    def step(self) -> Status:
        """RUNNING until the time is over."""
        return Status.SUCCESS if self.timer.over() else Status.RUNNING


#: BT.CPP's leaves, as robot behaviours of the mission language
BTCPP_LEAVES: tuple[type[BtLeaf], ...] = (
    Script,
    ScriptCondition,
    SetBlackboard,
    UnsetBlackboard,
    AlwaysSuccess,
    AlwaysFailure,
    Sleep,
)


class Precondition(bd.BtDecorator):
    """BT.CPP's ``Precondition``: the child while ``if`` held when it started, else the ``else`` status."""

    def __init__(self, name: str, child: Behaviour, script: Code_, otherwise: Status) -> None:
        super().__init__(name, child)
        self.script, self.otherwise = script, otherwise
        self.running = False

    def bt_tick(self) -> Any:
        """BT.CPP's ``PreconditionNode::tick``."""
        self.running = self.running or truth(run_script(self.script, self.name))
        if not self.running:
            return self.otherwise
        status = bn.execute(self.decorated)
        if status in (Status.SUCCESS, Status.FAILURE):
            bn.reset(self.decorated)
            self.running = False
        return status


def _text(value: Any) -> str:
    """A blackboard value as the text Switch compares."""
    return f"{value:f}" if isinstance(value, float) else str(value)


def _same(variable: str, case: str) -> bool:
    """BT.CPP's ``CheckStringEquality``: the same text, or the same number."""
    if variable == case:
        return True
    try:
        return float(variable) == float(case)
    except ValueError:
        return False


class Switch(bn.BtNode):
    """BT.CPP's ``SwitchN``: the child of the first ``case_i`` equal to ``variable``, else the last."""

    def __init__(self, name: str, children: list[Behaviour], variable: str, cases: list[str]) -> None:
        super().__init__(name, children)
        self.variable, self.cases = variable, cases
        self.running = -1

    def _value(self, text: str) -> str:
        """A port's text, or the blackboard entry it names (``{key}``)."""
        text = text.strip()
        if text.startswith("{") and text.endswith("}"):
            return _text(BOARD[text[1:-1]]) if text[1:-1] in BOARD else ""
        return text

    def bt_tick(self) -> Any:
        """BT.CPP's ``SwitchNode::tick``."""
        match = len(self.cases)
        variable = self._value(self.variable)
        for index, case in enumerate(self.cases):
            if _same(variable, self._value(case)):
                match = index
                break
        if self.running not in (-1, match):
            bn.reset(self.children[self.running])
        status = bn.execute(self.children[match])
        if status is bn.SKIPPED:
            self.running = -1
        elif status is Status.RUNNING:
            self.running = match
        else:
            self.halt()
        return status

    def halt(self) -> None:
        """No child running."""
        self.running = -1
        super().halt()


#: the pre-conditions in the order BT.CPP checks them, then the post-conditions
PRE = ("failure_if", "success_if", "skip_if", "while_true")
POST = ("on_halted", "on_failure", "on_success", "post")


class Conditioned(bn.BtNode):
    """A node with BT.CPP's pre/post-condition scripts (``scripts``: PRE and POST names)."""

    def __init__(self, name: str, child: Behaviour, scripts: dict[str, Code_]) -> None:
        super().__init__(name, [child])
        self.scripts = scripts

    def execute_tick(self) -> Any:
        """BT.CPP's ``TreeNode::executeTick`` with the conditions: pre, tick, post."""
        status = self._pre()
        if status is None:
            status = bn.execute(self.children[0])
            if status is bn.SKIPPED:  # the node's status as its tick left it (RUNNING if it set it)
                self.status = self.children[0].status
        elif status in (Status.SUCCESS, Status.FAILURE):
            self.children[0].status = status  # BT.CPP: the node and its conditions have one status
        if status in (Status.SUCCESS, Status.FAILURE):
            self._post("on_success" if status is Status.SUCCESS else "on_failure")
            self._post("post")
        if status is not bn.SKIPPED:
            self.status = status
        return status

    def _pre(self) -> Any:
        """The status a pre-condition gives instead of the tick, or None."""
        for key in PRE:
            script = self.scripts.get(key)
            if script is None:
                continue
            if self.status is Status.INVALID:
                holds = truth(run_script(script, self.name))
                if holds and key != "while_true":
                    return {"failure_if": Status.FAILURE, "success_if": Status.SUCCESS, "skip_if": bn.SKIPPED}[key]
                if not holds and key == "while_true":
                    return bn.SKIPPED
            elif self.status is Status.RUNNING and key == "while_true" and not truth(run_script(script, self.name)):
                self.halt()
                return bn.SKIPPED
        return None

    def _post(self, key: str) -> None:
        """Run the post-condition ``key`` if the node has it."""
        script = self.scripts.get(key)
        if script is not None:
            run_script(script, self.name)

    def halt(self) -> None:
        """BT.CPP's ``haltNode``: the node halted, then its ``_onHalted`` script."""
        super().halt()
        self._post("on_halted")

    def reset_status(self) -> None:
        """Reset to IDLE: the node it stands for too."""
        self.status = Status.INVALID
        bn.reset(self.children[0])
