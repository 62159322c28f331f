"""The shell of every page of ``grade --html``: one self-contained HTML file with its style inline.

A page loads nothing: no script, no font, no picture from elsewhere. Its Content-Security-Policy
says so to the browser too, so even a student name that escaped the escaping could not run or
fetch anything. Everything a page shows comes from results.json, which holds what students wrote
(names, file names, node names): it is written through :func:`esc` only.

Example:

>>> esc('<script>alert("x")</script>')
'&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;'
>>> fmt(8.0), fmt(7.25), fmt(None), fmt(float("nan")), fmt(True)
('8', '7.25', '–', '–', '–')
>>> page = shell("a <b>", "<p>hi</p>")
>>> page.startswith("<!doctype html>"), "<title>a &lt;b&gt;</title>" in page, "default-src 'none'" in page
(True, True, True)
"""

from __future__ import annotations

import html
import math
import re
import unicodedata
from typing import Any

# default-src 'none': no script, no fetch, no frame; only the inline style and data: icons
#: the most characters of a file name stem made from a name
NAME_LENGTH = 60
CSP = "default-src 'none'; style-src 'unsafe-inline'; img-src data:"

STATUS_LABELS = {"graded": "graded", "invalid": "invalid", "error": "error"}

CSS = """
:root { --ink: #1f2933; --muted: #616e7c; --line: #d9e2ec; --bg: #f5f7fa; --card: #fff;
  --ok: #2f855a; --ok-bg: #e3f5ea; --bad: #c53030; --bad-bg: #fde8e8; --warn: #b7791f; --warn-bg: #fdf3d8;
  --run: #2b6cb0; --run-bg: #e6f0fb; --never: #9aa5b1; --accent: #3c5a99; }
* { box-sizing: border-box; }
body { margin: 0; background: var(--bg); color: var(--ink);
  font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1120px; margin: 0 auto; padding: 20px 24px 48px; }
h1 { font-size: 1.6rem; margin: 0.2rem 0 0.3rem; overflow-wrap: break-word; }
h2 { font-size: 1.15rem; margin: 1.8rem 0 0.6rem; padding-bottom: 0.25rem; border-bottom: 1px solid var(--line); }
h3 { font-size: 1rem; margin: 1rem 0 0.4rem; }
a { color: var(--accent); }
.sub { color: var(--muted); margin: 0 0 0.6rem; overflow-wrap: break-word; }
.back { font-size: 0.9rem; }
code, .mono { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, "DejaVu Sans Mono", monospace;
  font-size: 0.85em; overflow-wrap: break-word; }
table { border-collapse: collapse; width: 100%; background: var(--card); border: 1px solid var(--line); }
th, td { text-align: left; padding: 6px 10px; border-bottom: 1px solid var(--line); vertical-align: top; }
th { background: #eef2f7; font-weight: 600; font-size: 0.88rem; color: #334e68; }
td.where { white-space: nowrap; }
td.num, th.num { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
tbody tr:hover { background: #f8fafc; }
.cards { display: flex; flex-wrap: wrap; gap: 12px; margin: 12px 0; }
.card { background: var(--card); border: 1px solid var(--line); border-radius: 8px; padding: 10px 16px;
  min-width: 150px; }
.card .big { font-size: 1.6rem; font-weight: 650; }
.card .label { color: var(--muted); font-size: 0.85rem; }
.badge { display: inline-block; padding: 1px 8px; border-radius: 10px; font-size: 0.8rem; font-weight: 600;
  white-space: nowrap; }
.badge.pass, .badge.graded { background: var(--ok-bg); color: var(--ok); }
.badge.fail { background: var(--bad-bg); color: var(--bad); }
.badge.invalid { background: var(--warn-bg); color: var(--warn); }
.badge.error { background: #efe4fb; color: #6b46c1; }
.badge.never { background: #eef0f3; color: #52606d; }
.score { font-size: 2.2rem; font-weight: 700; }
.score small { font-size: 1.1rem; color: var(--muted); font-weight: 500; }
.note { background: var(--card); border: 1px solid var(--line); border-left: 4px solid var(--accent);
  padding: 10px 14px; border-radius: 4px; margin: 10px 0; }
.note.bad { border-left-color: var(--bad); }
.note.warn { border-left-color: var(--warn); }
.messages { margin: 6px 0 0; padding-left: 1.2rem; }
.messages li { margin: 4px 0; }
.bars { background: var(--card); border: 1px solid var(--line); border-radius: 6px; padding: 8px 14px; }
.bar-row { display: grid; grid-template-columns: minmax(200px, 2fr) 3fr minmax(230px, 1.2fr); gap: 12px;
  align-items: center; padding: 6px 4px; border-radius: 4px; }
.bar-row.worst { background: var(--bad-bg); }
#criteria td:first-child { min-width: 170px; }
.bar-row .name { overflow-wrap: break-word; }
.bar { height: 14px; background: #e4e7eb; border-radius: 7px; overflow: hidden; }
.bar > span { display: block; height: 100%; background: var(--ok); }
.bar-row.worst .bar > span { background: var(--bad); }
.bar-row .what { color: var(--muted); font-size: 0.85rem; text-align: right; }
.tag { font-size: 0.75rem; font-weight: 700; color: var(--bad); text-transform: uppercase; margin-left: 6px; }
tr.fail td:first-child { border-left: 3px solid var(--bad); }
tr.pass td:first-child { border-left: 3px solid var(--ok); }
.figs { display: flex; flex-wrap: wrap; gap: 16px; }
figure { width: min-content; margin: 0; background: var(--card); border: 1px solid var(--line); border-radius: 6px;
  padding: 10px; }
figure svg { display: block; }
figcaption { font-size: 0.85rem; color: var(--muted); margin-top: 6px; min-width: 260px; }
.legend { display: flex; flex-wrap: wrap; gap: 4px 14px; font-size: 0.8rem; color: var(--muted); margin-top: 4px; }
.sw { display: inline-block; width: 12px; height: 12px; border-radius: 3px; vertical-align: -2px; margin-right: 4px; }
.cmd { display: block; background: #1f2933; color: #f5f7fa; padding: 5px 10px; border-radius: 4px;
  user-select: all; -webkit-user-select: all; cursor: text; }
.cmd::before { content: "$ "; color: #9aa5b1; }
tr.reproduce td { padding-top: 0; }
tr.run td { border-bottom: none; }
table.tree td { padding: 3px 10px; }
table.tree td.node { white-space: nowrap; }
table.tree .kind { color: var(--muted); font-size: 0.82rem; }
table.tree .ended { color: var(--muted); font-size: 0.78rem; white-space: normal; margin-left: 15px; }
tr.cov-ok td.node { border-left: 4px solid var(--ok); }
tr.cov-bad td.node { border-left: 4px solid var(--bad); }
tr.cov-mixed td.node { border-left: 4px solid var(--warn); }
tr.cov-running td.node { border-left: 4px solid var(--run); }
tr.cov-never td { color: var(--never); font-style: italic; background: #fafbfc; }
tr.cov-never td.node { border-left: 4px dashed var(--never); }
.guide { font-family: ui-monospace, monospace; color: #9fb3c8; white-space: pre; }
.dot { display: inline-block; width: 9px; height: 9px; border-radius: 50%; margin-right: 6px; }
.cov-ok .dot { background: var(--ok); } .cov-bad .dot { background: var(--bad); }
.cov-mixed .dot { background: var(--warn); } .cov-running .dot { background: var(--run); }
.cov-never .dot { background: transparent; border: 1.5px solid var(--never); }
.muted { color: var(--muted); }
footer { margin-top: 36px; color: var(--muted); font-size: 0.8rem; }
"""


def esc(value: object) -> str:
    """``value`` as text safe inside HTML (and SVG) text and quoted attributes: ``None`` is empty."""
    return html.escape("" if value is None else str(value), quote=True)


def num(value: Any) -> float | None:
    """``value`` as a finite float, or None (results are data: a bool, text or NaN is no number)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def fmt(value: Any, digits: int = 2) -> str:
    """A number for people: ``8`` rather than ``8.0``, at most ``digits`` decimals; '–' for none."""
    number = num(value)
    if number is None:
        return "–"
    return f"{round(number, digits):g}"


def as_list(value: Any) -> list[Any]:
    """``value`` if it is a list, else an empty list (a missing or malformed field shows nothing)."""
    return value if isinstance(value, list) else []


def as_dict(value: Any) -> dict[str, Any]:
    """``value`` if it is a mapping, else an empty one."""
    return value if isinstance(value, dict) else {}


def status_badge(status: Any) -> str:
    """A coloured label for a student's status (graded, invalid, error)."""
    label = STATUS_LABELS.get(str(status), str(status) or "unknown")
    css = str(status) if status in STATUS_LABELS else "error"
    return f'<span class="badge {css}">{esc(label)}</span>'


def pass_badge(passed: Any) -> str:
    """PASS or FAIL as a coloured label."""
    return '<span class="badge pass">pass</span>' if passed is True else '<span class="badge fail">fail</span>'


def where_code(where: Any) -> str:
    """A ``file:line`` as code, or nothing."""
    return f"<code>{esc(where)}</code>" if where else ""


def shell(title: str, body: str) -> str:
    """A whole HTML page: ``title`` is text (escaped here), ``body`` is HTML built with :func:`esc`."""
    return (
        "<!doctype html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f'<meta http-equiv="Content-Security-Policy" content="{CSP}">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        '<meta name="generator" content="thymio-bt grade">\n'
        '<link rel="icon" href="data:,">\n'
        f"<title>{esc(title)}</title>\n<style>{CSS}</style>\n</head>\n"
        f"<body>\n<main>\n{body}\n"
        "<footer>Made by <code>thymio-bt grade --html</code> from results.json; this page loads nothing "
        "from elsewhere.</footer>\n</main>\n</body>\n</html>\n"
    )


def safe_name(name: object) -> str:
    """A file name stem from a student's name: ASCII letters, digits, ``.``, ``_``, ``-`` only, not
    starting with a dot, at most :data:`NAME_LENGTH` characters; ``student`` if nothing is left."""
    ascii_name = unicodedata.normalize("NFKD", str(name)).encode("ascii", "ignore").decode()
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", ascii_name).strip("._-")[:NAME_LENGTH].rstrip("._-")
    return stem or "student"
