"""A user-defined behaviour, loaded by a mission's ``plugins:`` list (see spin_until_clear.yaml).

It turns in place until nothing is in front of the robot. Like the built-ins it has a pydantic
parameter model (validated, documented, in the JSON Schema) and gets the time limit, NO_ROBOT,
COLLISION, events and stopping for free from RobotBehaviour.
"""

import math

from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.base import BehaviourParams, FailureCode, RobotBehaviour
from thymio_bt.inputs.fields import AngularSpeed


class SpinUntilClearParams(BehaviourParams):
    """Turn until the front sensors see nothing."""

    rate: AngularSpeed = Field(1.0, gt=0, le=4, description="turn rate, left positive")


class SpinUntilClear(RobotBehaviour):
    """Turn in place until all five front sensors read nothing (inf)."""

    Params = SpinUntilClearParams
    moves = True

    def step(self) -> Status:
        scan = self.robot.proximity()  # None while the robot does not exist (deleted, not yet spawned)
        if scan is None:
            return self.fail(FailureCode.NO_ROBOT, "the robot does not exist")
        front = [v for k, v in scan.items() if k.startswith("front")]
        if all(math.isinf(v) for v in front):
            return Status.SUCCESS
        self.robot.drive(0.0, self.params.rate)
        self.feedback_message = "something ahead, turning"
        return Status.RUNNING
