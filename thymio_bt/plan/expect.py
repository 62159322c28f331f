"""What a mission counts as success, besides its tree succeeding: ``expect:`` in the mission, as data.

A tree can succeed in the wrong place (a wall follower that stops in the wrong pocket, a stop 2 cm
short because a sensor reads differently). So a mission may declare, checked on the run's
ground truth after it ends:

```yaml
expect:
  goal: {centre: [0.3, 0.489], radius: 1cm}        # where base_link must end
  no_collision: true
  # leaves_maze: true                             # base_link ends beyond the walls' box
  # dead_end: {distance: 5cm, side: $cell}         # facing a wall 5 cm away, walls on both sides
  max_time: 60s
  gaps:                                            # the front gap to the wall, by geometry,
    - {after: "course/part 1", distance: 5cm, tolerance: 3mm}   # when that node ended
```

Values may name the mission's parameters (``$cell``). ``goal`` and ``gaps`` are places of the
mission's own maze: in another maze (``--maze``, ``--start``) only the others are checked.

A run whose tree succeeds but whose expectations do not all hold ends FAILURE with code
``EXPECTATION`` and the failed ones in its reason; ``sweep`` counts it as a failure.
The verdict on a run is :func:`thymio_bt.run.verdict.check`.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from thymio_bt.inputs.fields import Duration, Length, Point

__all__ = ["DeadEnd", "Duration", "Expect", "GapExpectation", "GoalRegion"]


class GoalRegion(BaseModel):
    """A disc the robot's base_link must end in."""

    model_config = ConfigDict(extra="forbid")
    centre: Point = Field(description="the goal's centre [x, y]")
    radius: Length = Field(0.01, gt=0, le=10, description="how far from the centre still counts")


class GapExpectation(BaseModel):
    """The front gap (robot's nose to the wall ahead, by geometry) when a node ended."""

    model_config = ConfigDict(extra="forbid")
    after: str = Field(description="the node's path, or a glob on paths (e.g. 'course/part 1')")
    distance: Length = Field(gt=0, le=2, description="the gap expected")
    tolerance: Length = Field(0.003, gt=0, le=1, description="how far off still counts")


class DeadEnd(BaseModel):
    """The robot ends facing a wall, walls on both sides: a dead end, in any maze."""

    model_config = ConfigDict(extra="forbid")
    distance: Length = Field(gt=0, le=2, description="the front gap expected at the end")
    tolerance: Length = Field(0.005, gt=0, le=1, description="how far off still counts")
    side: Length = Field(
        0.15, gt=0, le=2, description="the side walls are at most this far from base_link (3/4 of a 0.2 m cell)"
    )


class Expect(BaseModel):
    """A mission's success criteria beyond its tree's status."""

    model_config = ConfigDict(extra="forbid")
    goal: GoalRegion | None = Field(None, description="where base_link must end")
    no_collision: bool = Field(False, description="no contact with a wall in the whole run")
    leaves_maze: bool = Field(False, description="base_link ends beyond the bounding box of the maze's walls")
    dead_end: DeadEnd | None = Field(None, description="the run ends in a dead end, this far from its wall")
    max_time: Duration | None = Field(None, gt=0, le=36000, description="the mission must end within this")
    gaps: list[GapExpectation] = Field(default=[], description="front gaps when nodes end")

    def without_places(self) -> Expect:
        """The criteria that hold anywhere (no goal, no gaps; ``leaves_maze`` and ``dead_end`` are
        any maze's): for a run in another maze or from another start."""
        return self.model_copy(update={"goal": None, "gaps": []})
