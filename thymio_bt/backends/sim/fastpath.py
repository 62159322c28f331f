"""pymunk calls without their per-call Python wrapping, for the simulation's hot path.

pymunk 7's ``Space.step`` wraps the C step in bookkeeping for deferred adds and removes and for
post-step callbacks, ``Space.segment_query_first`` builds three Python objects per ray, and a body's
``position`` a Vec2d per read. At 100
physics sub-steps and 70 rays per simulated second that wrapping cost as much as the physics itself
(profiled: ~1 µs of ~2 per sub-step, ~1 µs per ray). The simulation never changes the space from a
collision callback (they only count contacts) and adds or removes bodies only between steps, so it
may call the C functions directly. A body's position, angle and velocities are read and written in
Chipmunk's memory (a C call, which releases and takes back the GIL, costs three to four times more),
once a probe body has shown that the fields are where this module expects them. This is the only
module that touches pymunk's private handles; ``tests/test_sim.py`` checks that both paths give
bit-identical runs.

Example (a wall 2 cm thick whose face is at x = 0.5)::

    >>> space, anything = pymunk.Space(), pymunk.ShapeFilter()
    >>> wall = pymunk.Poly(space.static_body, [(0.5, -0.5), (0.52, -0.5), (0.52, 0.5), (0.5, 0.5)])
    >>> space.add(wall)
    >>> step, handle = stepper(space)
    >>> step(handle, 0.01)                         # same as space.step(0.01)
    >>> RayCaster(space).fan([(0, 0, 1, 0), (0, 0, -1, 0)], 0.0, 0.0, 1.0, 0.0, anything)   # where each ray hits
    [0.5, None]
    >>> reader = RayReader(space, {"ahead": (0.0, 0.0, 1.0, 0.0)}, 1.0, 0.0, anything)
    >>> reader.read("ahead", 0.1, 0.0, 1.0, 0.0)     # metres to the first hit, the body at x = 0.1
    0.4
    >>> PointDistance()(wall, (0.0, 0.0))          # (distance, nearest x, nearest y), as wall.point_query
    (0.5, 0.5, 0.0)
    >>> body = pymunk.Body(1.0, 1.0)
    >>> body.position, body.angle = (0.1, 0.2), 0.5
    >>> body_reader(body)()                        # (x, y, angle), as body.position and body.angle
    (0.1, 0.2, 0.5)
    >>> near = NearShapes(space, body, [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)], anything)
    >>> near.within(0.35), near.within(0.25)       # is any shape closer than that to the square?
    (True, False)
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Sequence
from functools import lru_cache, partial
from typing import Any

import pymunk
from pymunk._chipmunk import ffi, lib

#: Where pymunk 7's Chipmunk keeps a body's state, counted in doubles from the start of its cpBody
#: (after two function pointers, mass, moment, their inverses and the centre of gravity): velocity
#: (x, y), angle, angular velocity, and the transform (a, b, c, d, tx, ty; a, b the rotation).
_VELOCITY, _ANGLE, _SPIN, _TRANSFORM = 10, 14, 15, 17
_DOUBLES = _TRANSFORM + 6


def _view(body: pymunk.Body) -> memoryview[float]:
    """``body``'s cpBody state as doubles (see :data:`_VELOCITY`)."""
    return memoryview(ffi.buffer(body._body, 8 * _DOUBLES)).cast("d")


def _reader(m: memoryview[float]) -> Callable[[], tuple[float, float, float]]:
    """(x, y, angle) from a body's memory ``m``: the position as ``cpBodyGetPosition`` computes it,
    the transform applied to the origin (``a * 0 + c * 0 + tx``), which is the translation itself
    unless that is a zero, whose sign the sum decides."""
    a, b, c, d, tx, ty = range(_TRANSFORM, _TRANSFORM + 6)
    angle = _ANGLE

    def read() -> tuple[float, float, float]:
        return (m[tx] or (m[a] * 0.0 + m[c] * 0.0) + m[tx], m[ty] or (m[b] * 0.0 + m[d] * 0.0) + m[ty], m[angle])

    return read


def _same(xs: Sequence[float], ys: Sequence[float]) -> bool:
    """Equal, signed zeros included."""
    return all(x == y and math.copysign(1.0, x) == math.copysign(1.0, y) for x, y in zip(xs, ys, strict=True))


@lru_cache(maxsize=1)
def _layout_known() -> bool:
    """Whether this Chipmunk's cpBody holds its state where :data:`_VELOCITY` and the others say:
    checked once, on a probe body, against Chipmunk's own getters and setters (signed zeros too)."""
    body = pymunk.Body(1.0, 1.0)
    body.center_of_gravity = (0.25, -0.5)
    body.angle, body.position = 0.7, (0.125, -0.375)
    body.velocity, body.angular_velocity = (1.5, -2.5), 3.5
    h, m = body._body, _view(body)
    read = _reader(m)

    def agrees() -> bool:
        p, r, v = lib.cpBodyGetPosition(h), lib.cpBodyGetRotation(h), lib.cpBodyGetVelocity(h)
        return _same(
            (*read(), m[_VELOCITY], m[_VELOCITY + 1], m[_SPIN], m[_TRANSFORM], m[_TRANSFORM + 1]),
            (p.x, p.y, lib.cpBodyGetAngle(h), v.x, v.y, lib.cpBodyGetAngularVelocity(h), r.x, r.y),
        )

    if not agrees():
        return False
    m[_VELOCITY], m[_VELOCITY + 1], m[_SPIN] = -4.5, 5.5, -6.5  # written here, read by Chipmunk
    for a, c in ((0.5, -0.5), (-0.5, -0.5)):  # a zero translation: the sign comes from the sum
        m[_TRANSFORM], m[_TRANSFORM + 1], m[_TRANSFORM + 2], m[_TRANSFORM + 3] = a, a, c, c
        m[_TRANSFORM + 4], m[_TRANSFORM + 5] = -0.0, -0.0
        if not agrees():
            return False
    return True


def _memory(body: pymunk.Body) -> memoryview[float] | None:
    """``body``'s cpBody as doubles when its layout is the known one, else None. Reading or writing
    one costs a third of a C call; writing a velocity this way skips only Chipmunk's waking of a
    sleeping body, and the simulation never lets bodies sleep."""
    return _view(body) if _layout_known() else None


def body_reader(body: pymunk.Body) -> Callable[[], tuple[float, float, float]]:
    """A function giving ``body``'s position and angle (x, y, angle), the values Chipmunk's getters
    give, without pymunk's Vec2d and property wrapping (read on every tick and sub-step)."""
    m = _memory(body)
    if m is not None:
        return _reader(m)
    handle = body._body
    get_position, get_angle = lib.cpBodyGetPosition, lib.cpBodyGetAngle

    def read_by_calls() -> tuple[float, float, float]:
        p = get_position(handle)
        return p.x, p.y, get_angle(handle)

    return read_by_calls


def control_aimer(body: pymunk.Body, control: pymunk.Body) -> Callable[[float], None]:
    """A function that sets ``control``'s velocity to ``v`` along ``body``'s heading, as
    ``control.velocity = (v * cos(body.angle), v * sin(body.angle))`` does (re-aimed every sub-step
    while the robot turns)."""
    cos, sin = math.cos, math.sin
    m, c = _memory(body), _memory(control)
    if m is not None and c is not None:
        heading, vx, vy = _ANGLE, _VELOCITY, _VELOCITY + 1

        def aim(v: float) -> None:
            angle = m[heading]
            c[vx], c[vy] = v * cos(angle), v * sin(angle)

        return aim
    handle, target = body._body, control._body
    get_angle, set_velocity = lib.cpBodyGetAngle, lib.cpBodySetVelocity

    def aim_by_calls(v: float) -> None:
        angle = get_angle(handle)
        set_velocity(target, (v * cos(angle), v * sin(angle)))

    return aim_by_calls


def body_driver(body: pymunk.Body, control: pymunk.Body) -> Callable[[float, float, bool], None]:
    """A function that applies a new command (v, w): ``control`` aimed and spun as
    :func:`control_aimer` and :func:`spinner` do, and with ``seed`` ``body`` moved as
    ``body.velocity = v * body.rotation_vector; body.angular_velocity = w`` does."""
    m, c = _memory(body), _memory(control)
    if m is not None and c is not None:
        cos, sin = math.cos, math.sin
        heading, vx, vy, spin, rx, ry = _ANGLE, _VELOCITY, _VELOCITY + 1, _SPIN, _TRANSFORM, _TRANSFORM + 1

        def drive(v: float, w: float, seed: bool) -> None:
            angle = m[heading]
            c[vx], c[vy], c[spin] = v * cos(angle), v * sin(angle), w
            if seed:
                m[vx], m[vy], m[spin] = v * m[rx], v * m[ry], w

        return drive
    aim, turn, handle = control_aimer(body, control), spinner(control), body._body
    get_rotation, set_velocity, set_angular = lib.cpBodyGetRotation, lib.cpBodySetVelocity, lib.cpBodySetAngularVelocity

    def drive_by_calls(v: float, w: float, seed: bool) -> None:
        aim(v)
        turn(w)
        if seed:
            rot = get_rotation(handle)
            set_velocity(handle, (v * rot.x, v * rot.y))
            set_angular(handle, w)

    return drive_by_calls


def spinner(body: pymunk.Body) -> Callable[[float], None]:
    """A function that sets ``body``'s angular velocity (``body.angular_velocity = w``)."""
    m = _memory(body)
    if m is not None:
        index = _SPIN

        def spin(w: float) -> None:
            m[index] = w

        return spin
    return partial(lib.cpBodySetAngularVelocity, body._body)


def stepper(space: pymunk.Space) -> tuple[Callable[[Any, float], None], Any]:
    """A C function and ``space``'s handle: ``step(handle, dt)`` steps it like :meth:`pymunk.Space.step`
    minus its bookkeeping (the handle passed each call, not bound: ``functools.partial`` copies the
    arguments into a new tuple on every call, a hundred times a simulated second)."""
    return lib.cpSpaceStep, space._space


#: writes a segment's end points (x0, y0, x1, y1) into a buffer at an offset, as four doubles
_write_segment = struct.Struct("4d").pack_into


class _SegmentQuery:
    """The buffers of first-hit segment queries in one space.

    A ray's two end points are packed into a preallocated ``cpVect[2]`` in one ``struct`` call (four
    memoryview stores cost twice that) and passed as C structs (cffi converts a Python tuple to a
    struct field by field: 2.7 k instructions per query, four times the query itself); the space is
    passed as an argument, not bound by ``functools.partial`` (which copies the arguments into a new
    tuple per call); and the hit is read from the result's ``alpha``: Chipmunk leaves it at 1.0 when
    nothing is hit and records only hits below it.
    """

    __slots__ = ("_alpha", "_end", "_ends", "_info", "_points", "_query", "_result", "_space", "_start")

    def __init__(self, space: pymunk.Space) -> None:
        self._space, self._query = space._space, lib.cpSpaceSegmentQueryFirst
        self._info = ffi.new("cpSegmentQueryInfo *")
        self._result = memoryview(ffi.buffer(self._info)).cast("d")
        self._alpha = ffi.offsetof("cpSegmentQueryInfo", "alpha") // 8
        self._ends = ffi.new("cpVect[2]")
        self._start, self._end = self._ends[0], self._ends[1]
        self._points = memoryview(ffi.buffer(self._ends)).cast("d")  # x0, y0, x1, y1


def _c_filter(shape_filter: pymunk.ShapeFilter) -> tuple[Any, Any]:
    """``shape_filter`` as a C struct (cffi converts a tuple on every call), with the memory that
    owns it: keep both."""
    owner = ffi.new("cpShapeFilter *", tuple(shape_filter))
    return owner, owner[0]


class RayCaster(_SegmentQuery):
    """Fans of rays fixed in a body frame, cast together from the body's pose (see :class:`_SegmentQuery`)."""

    __slots__ = ("_filters",)

    def __init__(self, space: pymunk.Space) -> None:
        super().__init__(space)
        self._filters: dict[pymunk.ShapeFilter, tuple[Any, Any]] = {}

    def fan(
        self,
        rays: Sequence[tuple[float, float, float, float]],
        x: float,
        y: float,
        cos: float,
        sin: float,
        shape_filter: pymunk.ShapeFilter,
    ) -> list[float | None]:
        """For each ray ``(sx, sy, ex, ey)`` (start and end in a body frame, the body at ``(x, y)`` with
        a heading of this cosine and sine): where along it (0..1) it first touches a shape the filter
        admits, or None."""
        query, space, info, start, end, points = (
            self._query,
            self._space,
            self._info,
            self._start,
            self._end,
            self._points,
        )
        flt = self._filters.get(shape_filter)
        if flt is None:
            flt = self._filters[shape_filter] = _c_filter(shape_filter)
        result, flt, alpha_at, write = self._result, flt[1], self._alpha, _write_segment
        alphas: list[float | None] = []
        hit = alphas.append
        for sx, sy, ex, ey in rays:
            write(
                points,
                0,
                x + sx * cos - sy * sin,
                y + sx * sin + sy * cos,
                x + ex * cos - ey * sin,
                y + ex * sin + ey * cos,
            )
            query(space, start, end, 0.0, flt, info)
            alpha = result[alpha_at]
            hit(alpha if alpha < 1.0 else None)
        return alphas


class RayReader(_SegmentQuery):
    """Named rays fixed in a body frame, each ``reach`` long, read one at a time: the distance from a
    ray's start to the first shape the filter admits, at least ``floor``, or ``inf``. Its floats are
    :meth:`RayCaster.fan`'s (the same end points, query and ``alpha * reach``), for readings cast
    when a behaviour reads them (:mod:`.readings`)."""

    __slots__ = ("_filter", "_floor", "_owner", "_reach", "names", "rays")

    def __init__(
        self,
        space: pymunk.Space,
        rays: dict[str, tuple[float, float, float, float]],
        reach: float,
        floor: float,
        shape_filter: pymunk.ShapeFilter,
    ) -> None:
        super().__init__(space)
        self.rays = rays
        #: the rays' names, in their order
        self.names = tuple(rays)
        self._reach, self._floor = reach, floor
        self._owner, self._filter = _c_filter(shape_filter)

    def read(self, name: str, x: float, y: float, cos: float, sin: float) -> float:
        """Ray ``name``'s reading, the body at ``(x, y)`` with a heading of this cosine and sine
        (KeyError for a name it does not have)."""
        sx, sy, ex, ey = self.rays[name]
        _write_segment(
            self._points,
            0,
            x + sx * cos - sy * sin,
            y + sx * sin + sy * cos,
            x + ex * cos - ey * sin,
            y + ex * sin + ey * cos,
        )
        self._query(self._space, self._start, self._end, 0.0, self._filter, self._info)
        alpha = self._result[self._alpha]
        if alpha < 1.0:
            distance = alpha * self._reach
            return self._floor if distance < self._floor else distance
        return math.inf


class PointDistance:
    """The distance from a point to one shape and the shape's nearest point, as
    :meth:`pymunk.Shape.point_query` gives them, without its Python result objects."""

    __slots__ = ("_info", "_query")

    def __init__(self) -> None:
        self._query = lib.cpShapePointQuery
        self._info = ffi.new("cpPointQueryInfo *")

    def __call__(self, shape: pymunk.Shape, point: tuple[float, float]) -> tuple[float, float, float]:
        """(distance, x, y) from ``point`` to ``shape`` and its nearest point; negative inside it."""
        distance = self._query(shape._shape, point, self._info)
        nearest = self._info.point
        return distance, nearest.x, nearest.y


class NearShapes:
    """Whether any shape of a space lies closer than ``r`` to a body's convex hull: one C shape query
    with a probe (the hull grown by ``r``, never added to the space) and no Python callback.

    pymunk's ``Space.shape_query`` builds a Python object per overlap; here only the yes/no is
    needed, which lets the clearance tracker skip its exact (Python) computation in the common case.
    """

    __slots__ = ("_probe", "_query", "radius")

    def __init__(
        self,
        space: pymunk.Space,
        body: pymunk.Body,
        hull: Sequence[tuple[float, float]],
        shape_filter: pymunk.ShapeFilter,
    ) -> None:
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
