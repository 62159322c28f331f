"""Proximity readings cast when a behaviour reads them: the simulation's noise-free scans.

A noise-free reading depends on nothing but the refresh's pose and the walls, and behaviours read few
of the seven: MoveUntilWall and ChooseTurn read the front three, a turn by odometry none. So each ray
is cast on its first read, with :class:`~thymio_bt.backends.sim.fastpath.RayReader`, which sees walls only
(a robot spawned after the refresh is not seen, as it would not have been at the refresh).

:func:`lazy_scan` returns a read-only mapping (``types.MappingProxyType``) over a dict whose
``__missing__`` casts a sensor not read yet: a read of a sensor already cast stays in C (a mapping
with a Python ``__getitem__`` cost more per read than the rays it saved). Everything else (iteration,
``len``, ``in``, ``get``, ``keys``, ``values``, ``items``, ``==``, ``repr``, ``copy``, ``|``) sees all
seven sensors in their order, casting the rest first.

Example (a wall whose face is 0.5 m ahead)::

    >>> import pymunk
    >>> space = pymunk.Space()
    >>> space.add(pymunk.Poly(space.static_body, [(0.5, -0.5), (0.52, -0.5), (0.52, 0.5), (0.5, 0.5)]))
    >>> rays = {"ahead": (0.0, 0.0, 1.0, 0.0), "behind": (0.0, 0.0, -1.0, 0.0)}
    >>> scan = lazy_scan(RayReader(space, rays, 1.0, 0.0, pymunk.ShapeFilter()), (0.0, 0.0, 1.0, 0.0))
    >>> scan["ahead"]             # cast now
    0.5
    >>> dict(scan)                # the other one cast, in the sensors' order
    {'ahead': 0.5, 'behind': inf}
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from types import MappingProxyType
from typing import Any

from thymio_bt.backends.sim.fastpath import RayReader


class _Readings(dict[str, float]):
    """The readings of one refresh, each cast on its first read (only ever seen through a proxy)."""

    __slots__ = ("_at", "_complete", "_names", "_read")
    _at: tuple[float, float, float, float]  # the refresh's body pose: x, y, cos and sin of the heading
    _read: Callable[[str, float, float, float, float], float]
    _names: tuple[str, ...]
    _complete: bool  # every sensor cast, in the sensors' order

    def __missing__(self, name: str) -> float:
        x, y, cos, sin = self._at
        value = self[name] = self._read(name, x, y, cos, sin)
        return value

    def _all(self) -> _Readings:
        """Itself, every sensor cast and in the sensors' order."""
        if not self._complete:
            values = [self[name] for name in self._names]
            dict.clear(self)
            dict.update(self, zip(self._names, values, strict=True))
            self._complete = True
        return self

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def __contains__(self, name: object) -> bool:
        return name in self._names

    def get(self, name: str, default: Any = None) -> Any:
        return self[name] if name in self._names else default


def _after_all(method: Callable[..., Any]) -> Callable[..., Any]:
    """dict's ``method``, applied once every sensor is cast."""

    def completed(self: _Readings, *args: Any) -> Any:
        return method(self._all(), *args)

    completed.__name__ = completed.__qualname__ = method.__name__
    completed.__doc__ = method.__doc__
    return completed


for _method in ("keys", "values", "items", "copy", "__eq__", "__ne__", "__repr__", "__reversed__", "__or__", "__ror__"):
    setattr(_Readings, _method, _after_all(getattr(dict, _method)))


def lazy_scan(reader: RayReader, at: tuple[float, float, float, float]) -> Mapping[str, float]:
    """The readings of ``reader``'s rays from the body pose ``at`` (x, y, cos, sin of the heading),
    each cast when first read."""
    readings = _Readings()
    readings._at, readings._read, readings._names, readings._complete = at, reader.read, reader.names, False
    return MappingProxyType(readings)
