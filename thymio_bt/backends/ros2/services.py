"""ROS 2 service calls spread over a run's ticks, for the entity requests of :mod:`.backend`.

A call is a generator: each ``next()`` (one a tick) looks whether the service is there, then whether
it has answered; it ends with the response, or with None and its request FAILED with the reason.
No ROS import: ``client`` is an rclpy client, or anything with its three methods.

Example::

    >>> from types import SimpleNamespace as M
    >>> from thymio_bt.robot.interface import Request
    >>> request = Request("delete", "thymio")
    >>> steps = call_service(None, "/delete_entity", M(), request, timeout=1.0)
    >>> next(steps, "done"), request.state.name, request.reason
    ('done', 'FAILED', 'this robot has no delete service (topic map: delete: "")')
"""

from __future__ import annotations

import time
from collections.abc import Generator
from typing import Any

from thymio_bt.robot.interface import Request, RequestState


def fail(request: Request, reason: str) -> None:
    """Mark ``request`` FAILED, saying why."""
    request.state, request.reason = RequestState.FAILED, reason


def call_service(client: Any, name: str, message: Any, request: Request, timeout: float) -> Generator[None, None, Any]:
    """Call service ``name`` over later ticks: the response, or None (and ``request`` FAILED) when the
    service is not there, does not appear or answer within ``timeout`` seconds each, or refuses."""
    if client is None:
        fail(request, f'this robot has no {request.kind} service (topic map: {request.kind}: "")')
        return None
    deadline = time.monotonic() + timeout
    while not client.service_is_ready():
        if time.monotonic() > deadline:
            fail(request, f"service {name} is not available (waited {timeout:g} s)")
            return None
        yield
    future = client.call_async(message)
    while not future.done():
        if time.monotonic() > deadline + timeout:
            fail(request, f"service {name} did not answer within {timeout:g} s")
            return None
        yield
    response = future.result()
    if not response.success:
        fail(request, f"{name} refused: {response.status_message or 'no reason given'}")
        return None
    return response
