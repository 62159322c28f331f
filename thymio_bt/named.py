"""Objects named ``"module:attr"``: what a table names without importing it (a backend's factory and
options, a log format's reader and writer, a built-in node), imported when first asked for.

Example::

    >>> named("math:pi") > 3, named(len) is len
    (True, True)
"""

from __future__ import annotations

from importlib import import_module
from typing import Any


def named(ref: Any) -> Any:
    """``ref`` itself, or the object a ``"module:attr"`` string names (its module imported now)."""
    if not isinstance(ref, str):
        return ref
    module, _, attr = ref.partition(":")
    return getattr(import_module(module), attr)
