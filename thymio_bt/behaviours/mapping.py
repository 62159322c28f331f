"""Mapping and planning in mazes of square cells: what a micromouse does, as behaviours.

The robot keeps a :class:`~thymio_bt.maze.cellmap.CellMap` on the blackboard: the walls
seen so far, the cells visited, and where the maze's grid lies in the odometry frame.

- ``MapWalls`` looks at the side of its cell it faces (a few stationary readings; more when they
  disagree) and marks a wall or an opening. Facing a wall it also re-measures the robot's heading
  and its distance along it, which cancels the drift odometry builds up.
- ``PlanMove`` flood-fills the map towards a target region (walls not seen yet assumed open, or
  only known openings for the fast run) and writes the move: ``move_centre`` (back to the cell
  centre along the heading), ``move_turn`` (to face the next cell) and ``move_distance`` (cell centre to cell centre).
- ``MoveCells`` drives ``move_distance`` along the grid line, holding the corridor's centre with
  the side sensors (their readings correct the map's idea of where the robot is across the corridor).
- ``WallMapped`` and ``AtTarget`` are the conditions a tree needs around them.

``MoveCells`` lives in :mod:`thymio_bt.behaviours.move_cells` and the pose on the grid the four
share in :mod:`thymio_bt.behaviours.grid_pose`; their names still import from here.

A Thymio spinning at a cell centre clears the walls of an 18 cm contest cell by only 4 mm, so
every move ends where the map says the cell centre is, and the map keeps that true to a millimetre.

Example (YAML)::

    - repeat:
        until: {AtTarget: {target: centre}}
        do:
          sequence:
            - MapWalls
            - PlanMove: {target: centre}
            - MoveDistance: {distance: bb:move_centre}
            - TurnAngle: {angle: bb:move_turn}
            - MapWalls
            - selector: [WallMapped, {MoveCells: {distance: bb:move_distance}}]
"""

from __future__ import annotations

import math

from py_trees.common import Access, Status
from pydantic import Field

from thymio_bt.behaviours.base import ConditionBehaviour
from thymio_bt.behaviours.grid_pose import (
    HEADING,
    LEFT_OF,
    MAX_TILT,
    RIGHT_OF,
    MazeMapParams,
    OnGrid,
    Sensing,
    SensingParams,
    Side,
    Target,
)
from thymio_bt.behaviours.move_cells import MoveCells, MoveCellsParams
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import wrap_angle
from thymio_bt.maze.cellmap import STEPS, Cell

__all__ = [
    "HEADING",
    "LEFT_OF",
    "MAX_SHIFT",
    "MAX_TILT",
    "RIGHT_OF",
    "AtTarget",
    "AtTargetParams",
    "MapWalls",
    "MapWallsParams",
    "MazeMapParams",
    "MoveCells",
    "MoveCellsParams",
    "OnGrid",
    "PlanMove",
    "PlanMoveParams",
    "Sensing",
    "SensingParams",
    "Side",
    "Target",
    "WallMapped",
    "WallMappedParams",
]

#: a front-wall measurement that disagrees with the map's pose by more than this is not believed
MAX_SHIFT = 0.03


class MapWallsParams(SensingParams):
    """How the wall ahead is read."""

    readings: int = Field(
        3, ge=1, le=20, description="stationary readings per look; three times as many at most when they disagree"
    )


class MapWalls(Sensing):
    """Look at the side of the robot's cell it faces: a wall when the front sensor sees one within
    half a cell, an opening when it sees none; mark the cell visited. It stands still for
    ``readings`` ticks and reads on while they disagree (a wall at the edge of the sensor's range, a
    noisy reading); a side the map already knows takes one reading that agrees. Facing a wall it
    re-measures the heading (from where the two ±20° sensors hit
    it) and the distance to it (front sensor): the map's pose follows the robot, not odometry.

    Example (YAML)::

        - MapWalls: {cell: 18cm}
    """

    Params = MapWallsParams
    moves = True

    def start(self) -> None:
        """Forget the last look's readings."""
        self.samples: list[tuple[float, float, float]] = []

    def step(self) -> Status:
        """Stand still and read until the readings agree, then mark the side and fix the pose."""
        p = self.params
        self.robot.drive(0.0, 0.0)
        scan = self.robot.proximity()
        assert scan is not None
        self.samples.append((scan["front_center"], scan["front_center_left"], scan["front_center_right"]))
        near = [s[0] < p.cell / 2 for s in self.samples]
        cells, here, side = self.cell_map(), self.cell(), self.facing()
        known = cells.wall(here, side)
        confirmed = known is not None and near == [known]  # one reading agrees with the map: done
        if not confirmed and (
            len(self.samples) < p.readings or (0 < sum(near) < len(near) and len(near) < 3 * p.readings)
        ):
            self.feedback_message = f"reading ({len(self.samples)})"
            return Status.RUNNING
        wall = known if confirmed and known is not None else 2 * sum(near) > len(near)
        cells.mark(here, side, wall)
        cells.visited.add(here)
        if wall:
            self._relocate(here, side)
        self.extra = {"cell": list(here), "side": side, "wall": wall, "visited": len(cells.visited)}
        self.feedback_message = f"{side} of {here}: {'wall' if wall else 'open'}"
        return Status.SUCCESS

    def _relocate(self, here: Cell, side: str) -> None:
        """Correct the map's pose from the wall ahead, by the mean of the readings that saw it."""
        valid = [s for s in self.samples if all(math.isfinite(v) for v in s)]
        if valid:
            front, left, right = (sum(s[k] for s in valid) / len(valid) for k in range(3))
            self.fix_from_wall((front, left, right), self.centre_of(here), side, 1.0, 1.0, MAX_SHIFT)


class PlanMoveParams(MazeMapParams):
    """Where to go, and on which map."""

    target: Target = Field(
        "goal", description="the maze's goal region, the centre (the contest's goal block) or the start cell"
    )
    known_only: bool = Field(
        False,
        description="plan over known openings only and run straight through "
        "as many cells as the path goes straight (the fast run); else walls not "
        "seen yet are assumed open and the robot stops at every cell to look (exploration)",
    )


class PlanMove(OnGrid):
    """Flood-fill the map towards ``target`` and write the next move on the blackboard:
    ``move_centre`` (along the heading, back to the cell centre), ``move_turn`` (to face the next
    cell, relative, left positive) and ``move_distance`` (from this cell's centre to the next one's,
    or to the last cell of a straight run). In the target already: a zero move. FAILURE (NO_PATH) when the map
    leaves no way there.

    Example (YAML)::

        - PlanMove: {target: centre}
        - TurnAngle: {angle: bb:move_turn}
    """

    Params = PlanMoveParams
    instant = True

    def prepare(self) -> None:
        """The map's key, and the keys of the move written."""
        super().prepare()
        for key in ("move_centre", "move_turn", "move_distance"):
            self.board.register_key(key, access=Access.WRITE)

    def step(self) -> Status:
        """Flood-fill towards the target from the robot's cell and write the next move."""
        p = self.params
        cells, here = self.cell_map(), self.cell()
        targets = self.targets(p.target)
        if not targets:
            return self.fail(FailureCode.INVALID_INPUT, f"the maze declares no goal region (target: {p.target})")
        x, y, yaw = self.pose()
        cx, cy = self.centre_of(here)
        centre = (cx - x) * math.cos(yaw) + (cy - y) * math.sin(yaw)
        if here in targets:
            return self._write(centre, 0.0, 0.0)
        distance = cells.distances(targets, p.known_only)
        if here not in distance:
            return self.fail(FailureCode.NO_PATH, f"no way from cell {list(here)} to the {p.target} on the map")
        side = cells.next_side(here, self.facing(), distance, p.known_only)
        run = cells.straight_run(here, side, distance) if p.known_only else 1
        di, dj = STEPS[side]
        self.extra = {"cell": list(here), "to": [here[0] + run * di, here[1] + run * dj], "steps_left": distance[here]}
        return self._write(centre, wrap_angle(HEADING[side] - yaw), run * p.cell)

    def _write(self, centre: float, turn: float, ahead: float) -> Status:
        self.board.set("move_centre", centre)
        self.board.set("move_turn", turn)
        self.board.set("move_distance", ahead)
        return Status.SUCCESS


class WallMappedParams(MazeMapParams):
    """Is a wall mapped ahead?"""


class WallMapped(ConditionBehaviour, OnGrid):
    """SUCCESS when the map has a wall on the side of its cell the robot faces.

    Example (YAML)::

        - selector: [WallMapped, {MoveCells: {distance: bb:move_distance}}]
    """

    Params = WallMappedParams

    def step(self) -> Status:
        """Whether the map knows a wall on the side the robot faces; the feedback says which side."""
        cell, side = self.cell(), self.facing()
        wall = self.cell_map().wall(cell, side)
        self.say("side {} of cell {}: {}", side, cell, "a wall" if wall else "no wall on the map")
        return Status.SUCCESS if wall else Status.FAILURE


class AtTargetParams(MazeMapParams):
    """Is the robot in the target region?"""

    target: Target = Field(
        "goal", description="the maze's goal region, the centre (the contest's goal block) or the start cell"
    )


class AtTarget(ConditionBehaviour, OnGrid):
    """SUCCESS when the robot's cell (on the map's grid) is in the ``target`` region.

    Example (YAML)::

        - repeat: {until: {AtTarget: {target: centre}}, do: ...}
    """

    Params = AtTargetParams

    def step(self) -> Status:
        """Whether the robot's cell is one of the target's; the feedback says which cell."""
        cell = self.cell()
        inside = cell in self.targets(self.params.target)
        self.say("cell {}: {} the {}", cell, "in" if inside else "not in", self.params.target)
        return Status.SUCCESS if inside else Status.FAILURE
