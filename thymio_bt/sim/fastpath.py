"""pymunk calls without their per-call Python wrapping, for the simulation's hot path.

pymunk 7's ``Space.step`` wraps the C step in bookkeeping for deferred adds and removes and for
post-step callbacks, ``Space.segment_query_first`` builds three Python objects per ray, and a body's
``position`` a Vec2d per read. At 100
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
    near = NearShapes(space, body, hull, shape_filter)
    near.within(0.02)                          # is any shape closer than 2 cm to the hull?
"""

from __future__ import annotations

from functools import partial
from typing import Callable, Sequence

import pymunk
from pymunk._chipmunk import ffi, lib


def body_reader(body: pymunk.Body) -> Callable[[], tuple[float, float, float]]:
    """A function giving ``body``'s position and angle (x, y, angle) straight from Chipmunk, without
    pymunk's Vec2d and property wrapping (the same values: read on every tick and sub-step)."""
    handle = body._body
    get_position, get_angle = lib.cpBodyGetPosition, lib.cpBodyGetAngle

    def read() -> tuple[float, float, float]:
        p = get_position(handle)
        return p.x, p.y, get_angle(handle)
    return read


def body_mover(body: pymunk.Body) -> Callable[[float, float], None]:
    """A function that sets ``body``'s velocity to ``v`` along its heading and its angular velocity
    to ``w``, as ``body.velocity = v * body.rotation_vector; body.angular_velocity = w`` does."""
    handle = body._body
    get_rotation, set_velocity, set_angular = lib.cpBodyGetRotation, lib.cpBodySetVelocity, \
        lib.cpBodySetAngularVelocity

    def move(v: float, w: float) -> None:
        rot = get_rotation(handle)
        set_velocity(handle, (v * rot.x, v * rot.y))
        set_angular(handle, w)
    return move


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


class NearShapes:
    """Whether any shape of a space lies closer than ``r`` to a body's convex hull: one C shape query
    with a probe (the hull grown by ``r``, never added to the space) and no Python callback.

    pymunk's ``Space.shape_query`` builds a Python object per overlap; here only the yes/no is
    needed, which lets the clearance tracker skip its exact (Python) computation in the common case.
    """

    __slots__ = ("_probe", "_query", "radius")

    def __init__(self, space: pymunk.Space, body: pymunk.Body, hull: Sequence[tuple[float, float]],
                 shape_filter: pymunk.ShapeFilter) -> None:
        self._probe = pymunk.Poly(body, list(hull))
        self._probe.filter = shape_filter
        self._query = partial(lib.cpSpaceShapeQuery, space._space, self._probe._shape, ffi.NULL, ffi.NULL)
        self.radius = 0.0

    def within(self, radius: float) -> bool:
        """True when some shape the filter admits is closer than ``radius`` to the hull."""
        if radius != self.radius:
            self._probe.unsafe_set_radius(radius)
            self.radius = radius
        return bool(self._query())
