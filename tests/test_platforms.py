"""What docs/platforms.md (once the README) says of Windows, macOS and WSL, and --view's display check on each (#36)."""

import re
from pathlib import Path

from thymio_bt.viz.display import display_problem

PLATFORMS = Path(__file__).resolve().parents[1] / "docs" / "platforms.md"


def test_the_platforms_page_ends_with_a_section_on_windows_macos_and_wsl():
    text = PLATFORMS.read_text()
    headings = re.findall(r"^## (.+)$", text, re.M)
    assert headings[-1] == "Windows, macOS and WSL"
    section = " ".join(text.split("## Windows, macOS and WSL")[1].split())
    for said in ("Only Linux has been tried", "--view", "no display", "Playground", "ROS 2", "WSLg"):
        assert said in section, said


def test_the_display_check_asks_for_x11_or_wayland_only_where_they_are_the_display():
    assert display_problem({}, "linux") == "DISPLAY and WAYLAND_DISPLAY are not set"
    assert display_problem({"WAYLAND_DISPLAY": "wayland-0"}, "linux") is None  # WSLg, GNOME, ...
    assert display_problem({}, "win32") is None and display_problem({}, "darwin") is None  # the desktop's
    assert display_problem({"SDL_VIDEODRIVER": "dummy"}, "linux") is None  # offscreen, asked for
