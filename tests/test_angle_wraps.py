"""One angle wrap (issue 45): ``wrap_angle`` is the only formula of its kind; the few wraps that must
stay another formula say why where they are written. Those are not bit-identical to ``wrap_angle``
(math.remainder is exact where it rounds, atan2(sin, cos) keeps pi where it gives -pi), so routing
them through it would change runs: this test keeps the next reader from "fixing" them unawares."""

from __future__ import annotations

import math
import re
from pathlib import Path

import thymio_bt
from thymio_bt.robot.interface import wrap_angle

PACKAGE = Path(thymio_bt.__file__).parent
OTHER_WRAP = re.compile(r"math\.atan2\(math\.sin\(|math\.remainder\(")


def test_every_other_wrap_says_why_it_is_not_wrap_angle():
    unexplained = []
    for path in sorted(PACKAGE.rglob("*.py")):
        lines = path.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            code = line.split("#", 1)[0]
            if OTHER_WRAP.search(code) and not any("not wrap_angle" in x for x in (line, lines[i - 1] if i else "")):
                unexplained.append(f"{path.relative_to(PACKAGE)}:{i + 1}")
    assert unexplained == []


def test_the_other_wraps_really_differ_from_wrap_angle():
    """Why they are kept: both differ from wrap_angle in the last bit or at pi."""
    assert wrap_angle(math.pi) == -math.pi and math.atan2(math.sin(math.pi), math.cos(math.pi)) == math.pi
    assert math.remainder(math.pi, math.tau) == math.pi
    rounded = [x / 1000 for x in range(-3000, 3000) if wrap_angle(x / 1000) != math.remainder(x / 1000, math.tau)]
    assert rounded  # e.g. a small angle comes back an ulp off through (x + pi) % 2pi - pi
