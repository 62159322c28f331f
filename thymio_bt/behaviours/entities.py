"""Entity behaviours: delete the robot and spawn it elsewhere, like the course's Gazebo services."""

from __future__ import annotations

from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour, snapshot
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import Pose
from thymio_bt.inputs.fields import Duration, EntityName, Pose2D
from thymio_bt.robot.interface import ROBOT_ENTITY, Request, RequestState


class DeleteEntityParams(BehaviourParams):
    """Remove an entity from the world."""

    entity: EntityName = Field(ROBOT_ENTITY, description="the entity's name")
    timeout: Duration = Field(5.0, gt=0, le=3600, description="time limit in simulated seconds")


class DeleteEntity(RobotBehaviour):
    """Ask the backend to delete ``entity``; RUNNING until it is gone, FAILURE with its reason.

    Emits a ``delete_entity`` event with the robot's pose and proximity just before deletion.
    The entity is ``entity:`` (what Gazebo's services call ``name``); ``name:`` labels the node, as
    on every node, and is refused without ``entity:`` beside it.

    Example (YAML)::

        - DeleteEntity: {entity: thymio}
    """

    Params = DeleteEntityParams
    needs_robot = False
    fails_on_collision = False

    def start(self) -> None:
        """Note the robot's pose and readings for the event, and send the request."""
        self.before = snapshot(self.robot)
        self.request: Request = self.ctx.entities.request_delete(self.params.entity)

    def step(self) -> Status:
        """Wait for the request; log the deletion when it is served."""
        if self.request.state is RequestState.PENDING:
            self.feedback_message = f"deleting '{self.params.entity}'"
            return Status.RUNNING
        if self.request.state is RequestState.FAILED:
            return self.fail(FailureCode.ENTITY_ERROR, self.request.reason or "delete refused")
        self.ctx.events.emit(self.ctx.now(), "delete_entity", entity=self.params.entity, **self.before)
        self.feedback_message = f"deleted '{self.params.entity}'"
        return Status.SUCCESS


class SpawnEntityParams(BehaviourParams):
    """Put a fresh robot at a pose."""

    entity: EntityName = Field(ROBOT_ENTITY, description="the entity's name")
    pose: Pose2D = Field(
        description="x, y (m) and yaw (rad) of base_link, e.g. [0.5, 0.3, pi/2] or a named spawn of the maze"
    )
    timeout: Duration = Field(5.0, gt=0, le=3600, description="time limit in simulated seconds")


class SpawnEntity(RobotBehaviour):
    """Ask the backend to spawn ``entity`` at ``pose``; fails clearly while the name still exists.

    Example (YAML)::

        - SpawnEntity: {pose: [0.5, 0.3, pi/2]}
        - SpawnEntity: {pose: part2}          # a named spawn of the mission's maze
    """

    Params = SpawnEntityParams
    needs_robot = False
    fails_on_collision = False

    def start(self) -> None:
        """Send the spawn request."""
        self.target = Pose(*self.params.pose)
        self.request: Request = self.ctx.entities.request_spawn(self.params.entity, self.target)

    def step(self) -> Status:
        """Wait for the request; log the spawn when it is served."""
        if self.request.state is RequestState.PENDING:
            self.feedback_message = f"spawning '{self.params.entity}'"
            return Status.RUNNING
        if self.request.state is RequestState.FAILED:
            return self.fail(FailureCode.ENTITY_ERROR, self.request.reason or "spawn refused")
        self.ctx.events.emit(
            self.ctx.now(),
            "spawn_entity",
            entity=self.params.entity,
            pose={k: round(v, 6) for k, v in self.target.as_dict().items()},
        )
        self.feedback_message = f"spawned '{self.params.entity}' at ({self.target.x:g}, {self.target.y:g})"
        return Status.SUCCESS
