"""Place conditions: where base_link is, compared with the maze and with regions of it.

A wall follower composed of primitives needs to know when it is done: ``OutsideMaze`` is SUCCESS
once base_link has left the maze's bounding box (the ``ctx.bounds`` WallFollow also stops at),
``InRegion`` while base_link is in a rectangle, a disc, or the maze's goal region. Both read the
robot's own pose (odometry on a drifting robot), as every behaviour does; ``margin`` asks for a
robot clearly out, so that one whose odometry is a few centimetres off is not believed out while it
still stands beside the outer wall.

Example::

    >>> from thymio_bt.testing import run_tree, world
    >>> tree = {"repeat": {"until": "OutsideMaze", "do": {"MoveDistance": {"distance": "10cm"}}}}
    >>> open_end = world('''
    ... +--+--+
    ... |>
    ... +--+--+
    ... ''')
    >>> result = run_tree(tree, open_end, seconds=30)
    >>> result.status, result.collisions, round(result.final_pose.x, 2)
    (<RunStatus.SUCCESS: 'SUCCESS'>, 0, 0.5)
"""

from __future__ import annotations

import math

from py_trees.common import Status
from pydantic import Field, model_validator

from thymio_bt.behaviours.base import BehaviourParams, ConditionBehaviour, current_pose
from thymio_bt.enums import FailureCode
from thymio_bt.inputs.fields import Length, Point

__all__ = ["InRegion", "InRegionParams", "OutsideMaze", "OutsideMazeParams"]


class OutsideMazeParams(BehaviourParams):
    """Has base_link left the maze?"""

    margin: Length = Field(
        0.05,
        ge=0,
        le=1.0,
        description="how far beyond the maze's bounding box base_link must be (a drifted odometry "
        "is not believed out while the robot still stands beside the outer wall)",
    )


class OutsideMaze(ConditionBehaviour):
    """SUCCESS once base_link is more than ``margin`` outside the maze's bounding box.

    FAILURE while it is inside (or within ``margin`` of the walls' extent); FAILURE with code
    INVALID_INPUT where the backend knows no maze. The end condition of a wall follower made of
    primitives: in a perfect maze the only way out of the box is the exit gap.

    Example (YAML)::

        - repeat: {until: OutsideMaze, do: {sequence: [...]}}
    """

    Params = OutsideMazeParams

    def step(self) -> Status:
        """Compare base_link's pose with the maze's bounds grown by the margin."""
        bounds = self.ctx.bounds
        if bounds is None:
            return self.fail(FailureCode.INVALID_INPUT, "the maze's bounds are unknown to this backend")
        pose = current_pose(self.robot)
        xmin, ymin, xmax, ymax = bounds
        m = self.params.margin
        # how far out (> 0) or in (< 0) base_link is, by the nearest side of the box grown by the margin
        out = max(xmin - m - pose.x, pose.x - xmax - m, ymin - m - pose.y, pose.y - ymax - m)
        self.say("{:.3f} m {} the maze's box (margin included)", abs(out), "outside" if out > 0 else "inside")
        return Status.SUCCESS if out > 0 else Status.FAILURE


class InRegionParams(BehaviourParams):
    """Is base_link in a region?"""

    rect: tuple[Length, Length, Length, Length] | None = Field(
        None, description="a rectangle [xmin, ymin, xmax, ymax] (world frame)"
    )
    centre: Point | None = Field(None, description="a disc's centre [x, y] (world frame)")
    radius: Length = Field(0.05, gt=0, le=100, description="the disc's radius (with centre)")

    @model_validator(mode="after")
    def _one_region(self) -> InRegionParams:
        if self.rect is not None and self.centre is not None:
            raise ValueError("give a rect or a centre (with radius), not both")
        if self.rect is not None:
            xmin, ymin, xmax, ymax = self.rect
            if not (math.isfinite(xmin + ymin + xmax + ymax) and xmin < xmax and ymin < ymax):
                raise ValueError("rect is [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax")
        if self.centre is not None and not math.isfinite(self.centre[0] + self.centre[1]):
            raise ValueError("centre must be finite [x, y]")
        return self


class InRegion(ConditionBehaviour):
    """SUCCESS while base_link is in a rectangle, a disc, or the maze's goal region.

    The region is ``rect`` or the disc of ``radius`` about ``centre``; with neither, the maze's goal
    region (a micromouse maze's centre; FAILURE with code INVALID_INPUT when the maze declares
    none). FAILURE while base_link is outside it; borders count as inside.

    Example (YAML)::

        - InRegion: {rect: [-0.4, 0.2, -0.2, 0.5]}
        - InRegion: {centre: [0.3, 0.5], radius: 3cm}
        - InRegion: {}                                   # the maze's goal region
    """

    Params = InRegionParams

    def step(self) -> Status:
        """Whether base_link is in the region."""
        p = self.params
        pose = current_pose(self.robot)
        if p.centre is not None:
            distance = math.hypot(pose.x - p.centre[0], pose.y - p.centre[1])
            self.say("{:.3f} m from the centre", distance)
            return Status.SUCCESS if distance <= p.radius else Status.FAILURE
        if p.rect is not None:
            x0, y0, x1, y1 = p.rect
            inside = x0 <= pose.x <= x1 and y0 <= pose.y <= y1
        elif self.ctx.goal:
            inside = any(area.contains(pose.x, pose.y) for area in self.ctx.goal)
        else:
            return self.fail(FailureCode.INVALID_INPUT, "the maze declares no goal region: give a rect or a centre")
        self.say("base_link at ({:.3f}, {:.3f}): {}", pose.x, pose.y, "inside" if inside else "outside")
        return Status.SUCCESS if inside else Status.FAILURE
