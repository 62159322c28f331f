"""The ``str`` enums every room shares: :class:`TextEnum`, and :class:`FailureCode`, why a behaviour
or a run failed; and a tree node's status in each encoding a file or a wire gives it
(:data:`NODE_STATUSES`, :data:`STATUS_LETTER`). At the bottom of the package (it imports nothing of
it), so that a behaviour, a run, a grade or a log can name a code without importing the behaviours' base.

>>> STATUS_LETTER["SUCCESS"], NODE_STATUSES.index("FAILURE")  # a log's letter, BT.CPP's number
('S', 3)
"""

from __future__ import annotations

from enum import Enum

__all__ = ["NODE_STATUSES", "STATUS_LETTER", "FailureCode", "TextEnum"]

#: a tree node's statuses (py_trees' ``Status`` names), each at its number in BT.CPP's ``NodeStatus``
#: (IDLE 0, RUNNING 1, SUCCESS 2, FAILURE 3), the number Groot2 and the grader's wire send
NODE_STATUSES = ("INVALID", "RUNNING", "SUCCESS", "FAILURE")
#: a node status in one letter, as logs store it
STATUS_LETTER = dict(zip(NODE_STATUSES, "-RSF", strict=True))


class TextEnum(str, Enum):
    """A ``str`` enum that reads as its text (Python 3.11's ``StrEnum``; 3.10 lacks it): it equals,
    prints, formats and is written to JSON as the string it stands for, so a report or a message is
    the same whether it holds the member or the text.

    >>> f"[{FailureCode.TIMEOUT}]", str(FailureCode.TIMEOUT), FailureCode.TIMEOUT == "TIMEOUT"
    ('[TIMEOUT]', 'TIMEOUT', True)
    """

    def __str__(self) -> str:
        return str.__str__(self)

    def __format__(self, spec: str) -> str:
        return str.__format__(self, spec)


class FailureCode(TextEnum):
    """Why a behaviour, or a run, failed, in the style of Nav2's error codes.

    These are the built-in codes; a plugin behaviour may fail with a code of its own, any
    UPPER_SNAKE_CASE string (``self.fail("LINE_LOST", "...")``): reports carry codes as their text.
    """

    TIMEOUT = "TIMEOUT"
    COLLISION = "COLLISION"
    NO_ROBOT = "NO_ROBOT"
    NO_WALL = "NO_WALL"
    INVALID_INPUT = "INVALID_INPUT"
    ENTITY_ERROR = "ENTITY_ERROR"
    #: not an error: the way is blocked, and the tree is expected to react (e.g. avoidance turns away)
    BLOCKED = "BLOCKED"
    FAILED = "FAILED"
    #: the robot moves but gets no closer to its goal (e.g. circling a goal tighter than it can hold)
    NO_PROGRESS = "NO_PROGRESS"
    #: the map leaves no way to the target
    NO_PATH = "NO_PATH"
    #: the behaviour's code raised an exception (or called sys.exit): a bug, reported with its place
    EXCEPTION = "EXCEPTION"
    # the run's own codes: a run cut short (thymio_bt.run.result.Ending), or judged when it ended
    #: a real robot stopped answering (:class:`~thymio_bt.robot.interface.RobotLost`)
    ROBOT_LOST = "ROBOT_LOST"
    #: the backend raised: a bug of the backend (a plugin's, say)
    BACKEND_ERROR = "BACKEND_ERROR"
    #: a signal (Ctrl-C, SIGTERM) ended the run
    INTERRUPTED = "INTERRUPTED"
    #: a tick hook raised :class:`~thymio_bt.errors.StopRun` (the viewer was closed, say)
    STOPPED = "STOPPED"
    #: the tree succeeded but the mission's ``expect:`` criteria did not all hold
    EXPECTATION = "EXPECTATION"
