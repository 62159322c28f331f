"""Two pymunk calls without their per-call Python wrapping, for the simulation's hot path.

pymunk 7's ``Space.step`` wraps the C step in bookkeeping for deferred adds and removes and for
post-step callbacks, and ``Space.segment_query_first`` builds three Python objects per ray. At 100
physics sub-steps and 70 rays per simulated second that wrapping cost as much as the physics itself
(profiled: ~1 µs of ~2 per sub-step, ~1 µs per ray). The simulation never changes the space from a
collision callback (they only count contacts) and adds or removes bodies only between steps, so it
may call the C functions directly. This is the only module that touches pymunk's private ``_space``
handle; ``tests/test_sim.py`` checks that both paths give bit-identical runs.

Example::

    step = stepper(space)
    step(0.01)                                 # same as space.step(0.01)
    ray = RayCaster(space)
    ray.alpha((0, 0), (1, 0), shape_filter)    # fraction along the segment of the first hit, or None
"""

from __future__ import annotations

from functools import partial
from typing import Callable

import pymunk
from pymunk._chipmunk import ffi, lib


def stepper(space: pymunk.Space) -> Callable[[float], None]:
    """A function that steps ``space`` by ``dt`` like :meth:`pymunk.Space.step`, minus its bookkeeping."""
    return partial(lib.cpSpaceStep, space._space)


class RayCaster:
    """First-hit segment queries in one space, reusing one result buffer."""

    __slots__ = ("_query", "_info", "_null")

    def __init__(self, space: pymunk.Space) -> None:
        self._query = partial(lib.cpSpaceSegmentQueryFirst, space._space)
        self._info = ffi.new("cpSegmentQueryInfo *")
        self._null = ffi.NULL

    def alpha(self, start: tuple[float, float], end: tuple[float, float],
              shape_filter: pymunk.ShapeFilter) -> float | None:
        """Where along start→end (0..1) the segment first touches a shape the filter admits, or None."""
        if self._query(start, end, 0.0, shape_filter, self._info) == self._null:
            return None
        return self._info.alpha
