"""One self-contained HTML page per run (or two runs side by side): ``view LOG``, ``run --html``.

The page is one file: the runs' data (:mod:`thymio_bt.viz.page_data`) as JSON in a
``<script type="application/json">``, the viewer's own JavaScript and CSS (the parts of
``viz/web/viewer/`` in :data:`SCRIPT_PARTS` order, one script, and ``viz/web/viewer.css``: plain files
of this package, read when a page is written) inline, and the maze, robot
and signals drawn by the script as SVG. No network, no CDN: a Content-Security-Policy lets the page
load nothing from outside, so it works from ``file://``, offline, in an iframe (Jupyter) and from the
live server (:mod:`thymio_bt.viz.live`). docs/viewer.md gives the page's DOM contract.

Example:

>>> from thymio_bt.maze import Maze
>>> from thymio_bt.logs.recording import Recording
>>> text = page_html([page_data(Recording(maze=Maze(), mission="m<1>"))])
>>> text.startswith("<!doctype html>"), "<title>m&lt;1&gt; - thymio-bt</title>" in text, "m<1>" in text
(True, True, False)
>>> embedded_json({"a": "</script><!--"})
'{"a":"\\\\u003c/script\\\\u003e\\\\u003c!--"}'
"""

from __future__ import annotations

import html
import json
from importlib.resources import files
from pathlib import Path
from typing import Any

from thymio_bt.logs.recording import Recording
from thymio_bt.outputs import Output
from thymio_bt.viz.page_data import page_data

#: what the page may load: its own inline script and style, pictures as data: URLs; a live page
#: also its server (``connect-src 'self'``)
POLICY = "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:"


#: the viewer's script, part by part (``viz/web/viewer/NAME.js``), in the order they run: each part
#: declares what the later ones use, in one function scope the page wraps them in
SCRIPT_PARTS = ("helpers", "runs", "maze", "trees", "timeline", "breakpoints", "moving", "live")
#: what the viewer's script is, at the top of the page's script
SCRIPT_HEAD = """/* thymio-bt's run viewer: one run (or two) of a mission, at any tick.
 *
 * Reads the JSON of <script id="run-data"> (thymio_bt/viz/page_data.py writes it) and draws the
 * maze, the robot with its rays, the path, the tree with each node's status, the blackboard, the
 * signals and the events as SVG and HTML. Plain JavaScript, no library, no request: the page works
 * from file:// and offline. The DOM contract that outside checks read is in docs/viewer.md:
 * [data-node][data-status] per tree node, [data-pose] on the robot, [data-time] (and data-tick) on
 * the clock, data-divergence on <html>, and #t= / #tick= deep links.
 */
"use strict";
"""


def asset(name: str) -> str:
    """The text of the viewer's file ``name`` (``viewer.css``, ``viewer/maze.js``...) shipped in this package."""
    return files("thymio_bt.viz").joinpath("web").joinpath(name).read_text(encoding="utf-8")


def viewer_script() -> str:
    """The viewer's script: its parts in order, in one function scope (nothing leaks to ``window``).

    >>> script = viewer_script()
    >>> script.count("(function () {"), script.rstrip().endswith("})();"), "class Run" in script
    (1, True, True)
    """
    parts = "\n".join(asset(f"viewer/{name}.js") for name in SCRIPT_PARTS)
    return f"{SCRIPT_HEAD}\n(function () {{\n{parts}}})();\n"


def embedded_json(data: Any) -> str:
    """``data`` as JSON safe inside a ``<script>`` element: no ``<``, ``>`` or ``&`` left to end it."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def page_html(
    runs: list[dict[str, Any]],
    divergence: dict[str, Any] | None = None,
    *,
    live: bool = False,
    title: str | None = None,
) -> str:
    """The page for ``runs`` (one or two :func:`~thymio_bt.viz.page_data.page_data`), with the two
    runs' first ``divergence`` (``time``, ``tick``, ``reason``) when there is one; a ``live`` page
    polls its server for the ticks still to come."""
    title = title or " vs ".join(str(run["label"]) for run in runs) or "run"
    policy = POLICY + ("; connect-src 'self'" if live else "")
    data = {"runs": runs, "divergence": divergence, "live": live}
    return (
        "<!doctype html>\n"
        '<html lang="en"><head><meta charset="utf-8">\n'
        f'<meta http-equiv="Content-Security-Policy" content="{policy}">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        '<link rel="icon" href="data:,">\n'
        f"<title>{html.escape(title)} - thymio-bt</title>\n"
        f"<style>\n{asset('viewer.css')}</style>\n"
        "</head><body>\n"
        '<noscript><p class="noscript">This page draws the run with JavaScript: allow scripts.</p></noscript>\n'
        '<div id="app" class="app"></div>\n'
        f'<script type="application/json" id="run-data">{embedded_json(data)}</script>\n'
        f"<script>\n{viewer_script()}</script>\n"
        "</body></html>\n"
    )


def write_page(
    recordings: list[Recording],
    path: Path | str,
    divergence: dict[str, Any] | None = None,
    labels: list[str] | None = None,
) -> Path:
    """Write the page of one or two ``recordings`` to ``path`` (whole or not at all); the path."""
    labels = labels or [""] * len(recordings)
    return write_runs([page_data(r, label) for r, label in zip(recordings, labels, strict=True)], path, divergence)


def write_runs(runs: list[dict[str, Any]], path: Path | str, divergence: dict[str, Any] | None = None) -> Path:
    """Write the page of ``runs`` (:func:`~thymio_bt.viz.page_data.page_data`, perhaps with more said,
    such as where a what-if run was simulated) to ``path``, whole or not at all; the path."""
    out = Output(path, "--html", stdout_ok=False)
    out.write_text(page_html(runs, divergence))
    return out.path
