"""Is there a display for ``--view``? Asked before anything runs, so that a run never goes on for
minutes in real time showing nothing.

Without a display SDL does not fail: it falls back to its ``offscreen`` video driver and "shows" the
window nowhere. So ``--view`` refuses at once, exit 2, ``no display: ...``, naming what works
without one, unless the user asked SDL for a driver (``SDL_VIDEODRIVER=dummy`` draws offscreen on
purpose, as the tests do). On Linux (and the BSDs) a display is ``DISPLAY`` (X11) or
``WAYLAND_DISPLAY``; elsewhere (Windows, macOS) the desktop is assumed and SDL's choice is checked.

Example (the environment and the platform passed in, as the command line reads them)::

    >>> display_problem({"DISPLAY": ":0"}, "linux") is None
    True
    >>> display_problem({}, "linux")
    'DISPLAY and WAYLAND_DISPLAY are not set'
    >>> display_problem({"SDL_VIDEODRIVER": "dummy"}, "linux") is None  # offscreen, asked for
    True
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping

from thymio_bt.errors import UserError

#: SDL's video drivers that draw nowhere: what it falls back to when no display answers
HEADLESS_DRIVERS = ("offscreen", "dummy")

#: how to install pygame, from PyPI and from a checkout of the repository
INSTALL_HINT = "pip install 'thymio-bt[viz]', or in a checkout: pip install -e '.[viz]'"


def display_problem(env: Mapping[str, str] | None = None, platform: str | None = None) -> str | None:
    """Why no window can be shown, from the environment alone (None: SDL may find a display)."""
    env = os.environ if env is None else env
    platform = sys.platform if platform is None else platform
    if env.get("SDL_VIDEODRIVER"):
        return None  # the user chose SDL's driver (dummy: offscreen on purpose)
    x11_or_wayland = platform.startswith(("linux", "freebsd", "openbsd", "netbsd"))
    if x11_or_wayland and not (env.get("DISPLAY") or env.get("WAYLAND_DISPLAY")):
        return "DISPLAY and WAYLAND_DISPLAY are not set"
    return None


def require_display(instead: str) -> None:
    """Refuse ``--view`` (a :class:`UserError`, exit 2) when no window can be shown: the environment
    says so, or SDL, asked for a window, fell back to a driver that draws nowhere; ``instead`` names
    the options that work without a display. Opens SDL's video (pygame), as the window will."""
    if os.environ.get("SDL_VIDEODRIVER"):
        return  # the user chose SDL's driver: a window there, or offscreen on purpose
    problem = display_problem() or _sdl_fallback()
    if problem is not None:
        raise UserError(f"no display: --view needs a window, and {problem} (hint: {instead})")


def _sdl_fallback() -> str | None:
    """Why SDL cannot show a window (its fallback to a headless driver), after initialising it."""
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # no banner on stdout
    try:
        import pygame
    except ImportError:
        raise UserError(f"pygame is not installed (hint: {INSTALL_HINT})") from None
    try:
        pygame.display.init()
    except pygame.error as exc:
        return f"SDL found none: {exc}"
    driver = pygame.display.get_driver()
    if driver in HEADLESS_DRIVERS:
        return f"SDL found none (it fell back to its '{driver}' driver)"
    return None
