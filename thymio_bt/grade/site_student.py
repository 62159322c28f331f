"""One student's page of ``grade --html``: why the score is what it is, and where to look.

The score; each criterion with its points, verdict, feedback and ``file:line``; the palette's
findings; a picture per variant (maze, path, failing moments); the runs that went wrong with the
command that replays each; the tree with what every node reached over all runs. An invalid
submission's page shows why it was not run.

Example:

>>> student = {"name": "<b>eve</b>", "status": "invalid", "score": 0, "max": 10,
...            "messages": ["eve.yaml:3: unknown node type 'Foo'"], "criteria": [], "runs": []}
>>> page = student_page({"assignment": {"name": "a1"}}, student, {})
>>> "&lt;b&gt;eve&lt;/b&gt;" in page, "<b>eve" in page, "unknown node type &#x27;Foo&#x27;" in page
(True, False, True)
"""

from __future__ import annotations

from typing import Any

from thymio_bt.grade.site_page import (
    as_dict,
    as_list,
    esc,
    fmt,
    num,
    pass_badge,
    shell,
    status_badge,
    where_code,
)
from thymio_bt.grade.site_svg import trajectory_svg
from thymio_bt.maze.model import Maze

_OTHER_SEED = '<span><span class="sw" style="background:#dd6b20"></span>went wrong in another seed\'s run</span>'
OUTCOMES = {
    "ok": "reached SUCCESS only",
    "bad": "reached FAILURE only",
    "mixed": "reached both SUCCESS and FAILURE",
    "running": "ticked, never finished",
    "never": "never ticked",
}


def run_missed(run: dict[str, Any]) -> list[str]:
    """The criteria ``run`` failed (by name)."""
    return [name for name, v in as_dict(run.get("criteria")).items() if as_dict(v).get("passed") is False]


def run_failed(run: dict[str, Any]) -> bool:
    """Whether a run went wrong: it did not end in SUCCESS, or it missed a criterion."""
    return run.get("status") != "SUCCESS" or bool(run_missed(run))


def _header(results: dict[str, Any], student: dict[str, Any]) -> str:
    assignment = as_dict(results.get("assignment"))
    title = assignment.get("title") or assignment.get("name") or "assignment"
    maximum = student.get("max", assignment.get("max"))
    return (
        f'<p class="back"><a href="../index.html">&larr; class page: {esc(title)}</a></p>'
        f'<h1 class="student-name">{esc(student.get("name"))}</h1>'
        f'<p class="sub"><code>{esc(student.get("file"))}</code> {status_badge(student.get("status"))}</p>'
        f'<div class="score" id="score">{fmt(student.get("score"))} <small>/ {fmt(maximum)}</small></div>'
    )


def _messages(student: dict[str, Any]) -> str:
    messages = as_list(student.get("messages"))
    if not messages:
        return ""
    why = "was not graded" if student.get("status") != "graded" else "has these messages"
    items = "".join(f"<li><code>{esc(m)}</code></li>" for m in messages)
    return (
        f'<div class="note bad" id="messages"><strong>This submission {why}:</strong>'
        f'<ul class="messages">{items}</ul></div>'
    )


def _criteria(student: dict[str, Any]) -> str:
    rows = []
    messages = {str(m) for m in as_list(student.get("messages"))}
    for c in as_list(student.get("criteria")):
        c = as_dict(c)
        verdict = "pass" if c.get("passed") is True else "fail"
        runs = f"{fmt(c.get('passed_runs'))} / {fmt(c.get('runs'))}" if num(c.get("runs")) else "–"
        feedback = c.get("feedback")
        if feedback is not None and str(feedback) in messages:  # said once, above the table
            feedback = "not run: see why above"
        rows.append(
            f'<tr class="criterion {verdict}"><td>{esc(c.get("name"))}</td>'
            f'<td class="num">{fmt(c.get("earned"))} / {fmt(c.get("points"))}</td>'
            f'<td>{pass_badge(c.get("passed"))}</td><td class="num">{runs}</td>'
            f"<td>{esc(feedback)}{_per_variant(c)}</td><td class=where>{where_code(c.get('where'))}</td></tr>"
        )
    if not rows:
        return '<h2>Criteria</h2><p class="muted">No criterion was judged.</p>'
    return (
        '<h2>Criteria</h2><table id="criteria"><thead><tr><th>Criterion</th><th class="num">Points</th>'
        '<th>Result</th><th class="num">Runs passed</th><th>Feedback</th><th>Where</th></tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table>"
    )


def _per_variant(criterion: dict[str, Any]) -> str:
    """A criterion's points in each variant, and what went wrong there (shared credit)."""
    variants = [as_dict(v) for v in as_list(criterion.get("variants"))]
    if len(variants) < 2 or criterion.get("passed") is True:
        return ""
    items = "".join(
        f"<li>{esc(v.get('name'))}: {fmt(v.get('earned'))} points"
        f"{': ' + esc(v.get('feedback')) if v.get('feedback') else ''}</li>"
        for v in variants
    )
    return f'<ul class="per-variant">{items}</ul>'


def _palette(student: dict[str, Any]) -> str:
    findings = [as_dict(f) for f in as_list(student.get("palette"))]
    if not findings:
        return ""
    rows = "".join(
        f'<tr class="fail"><td><code>{esc(f.get("node"))}</code></td><td>{esc(f.get("rule"))}</td>'
        f"<td>{esc(f.get('message'))}</td><td class=where>{where_code(f.get('where'))}</td>"
        f'<td class="num">&minus;{fmt(f.get("points"))}</td></tr>'
        for f in findings
    )
    return (
        '<h2>Palette: nodes the assignment does not allow</h2><table id="palette"><thead><tr><th>Node</th>'
        '<th>Rule</th><th>Message</th><th>Where</th><th class="num">Points</th></tr></thead>'
        f"<tbody>{rows}</tbody></table>"
    )


def _pictures(results: dict[str, Any], student: dict[str, Any], mazes: dict[str, Maze | str]) -> str:
    runs = [as_dict(r) for r in as_list(student.get("runs"))]
    if not runs:
        return ""
    figures = []
    for variant in _variants_run(results, runs):
        name = str(variant.get("name"))
        mine = [r for r in runs if str(r.get("variant")) == name]
        if mine and variant.get("visibility") != "hidden":  # a hidden world is not drawn
            figures.append(_figure(name, variant, mine, mazes.get(name)))
    return f'<h2>Where the robot went</h2><div class="figs">{"".join(figures)}</div>'


def _variants_run(results: dict[str, Any], runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The assignment's variants, then any other variant the runs name (results from elsewhere)."""
    variants = [as_dict(v) for v in as_list(as_dict(results.get("assignment")).get("variants"))]
    known = {str(v.get("name")) for v in variants}
    return variants + [{"name": n} for n in dict.fromkeys(str(r.get("variant")) for r in runs) if n not in known]


def _figure(name: str, variant: dict[str, Any], mine: list[dict[str, Any]], maze: Maze | str | None) -> str:
    """One variant's figure: its maze with the paths of the student's runs in it (``mine``), what
    went wrong numbered below, and the maze's problem when it could not be read (``maze`` a str)."""
    svg, marks = trajectory_svg(maze if isinstance(maze, Maze) else None, variant, mine)
    failed = sum(run_failed(r) for r in mine)
    traced = next((r for r in mine if as_list(r.get("trajectory"))), None)
    caption = f"variant {name}: {failed} of {len(mine)} runs went wrong"
    if traced is not None:
        caption += f"; the path drawn is seed {traced.get('seed')}'s"
    notes = "".join(
        f'<li style="color:{m.colour}"><span style="color:#1f2933">{esc(m.text)} '
        f'<span class="muted">({esc(m.seed_text)})</span></span></li>'
        for m in marks
    )
    other = any(not m.traced for m in marks)
    problem = f'<p class="note warn">{esc(maze)}</p>' if isinstance(maze, str) else ""
    return (
        f'<figure class="variant" data-variant="{esc(name)}">{svg}<figcaption>{esc(caption)}'
        '<div class="legend"><span><span class="sw" style="background:#2b6cb0"></span>path</span>'
        '<span><span class="sw" style="background:#2f855a"></span>start</span>'
        '<span><span class="sw" style="background:#1f2933"></span>end</span>'
        '<span><span class="sw" style="background:#c53030"></span>went wrong (numbered below)</span>'
        f"{_OTHER_SEED if other else ''}</div>"
        f"{f'<ol class=messages>{notes}</ol>' if notes else ''}{problem}</figcaption></figure>"
    )


def _failed_runs(student: dict[str, Any]) -> str:
    runs = [as_dict(r) for r in as_list(student.get("runs"))]
    failed = [r for r in runs if run_failed(r)]
    if not runs:
        return ""
    if not failed:
        return f'<h2>Runs</h2><p class="muted">All {len(runs)} runs ended in SUCCESS and met every criterion.</p>'
    rows = []
    for r in failed:
        status = " ".join(dict.fromkeys(str(v) for v in (r.get("status"), r.get("code")) if v))  # "TIMEOUT" once
        missed = ", ".join(run_missed(r)) or "–"
        node = ""
        if r.get("failed_path"):
            node = f"<br>at <code>{esc(r.get('failed_path'))}</code> {where_code(r.get('where'))}"
        reason = f"<br>{esc(r.get('reason'))}" if r.get("reason") else ""
        rows.append(
            f'<tr class="run fail"><td>{esc(r.get("variant"))}</td><td class="num">{esc(r.get("seed"))}</td>'
            f"<td>{esc(status)}{reason}{node}</td><td>{esc(missed)}</td>"
            f'<td class="num">{fmt(r.get("sim_time"), 1)} s</td><td class="num">{fmt(r.get("collisions"))}</td></tr>'
        )
        if r.get("replay_page"):  # a page of the viewer, at the failing moment (not a hidden world's for students)
            rows.append(
                f'<tr class="replay"><td colspan="6"><a class="replay" href="{esc(r.get("replay_page"))}">'
                "watch this run in the browser, from where it went wrong</a></td></tr>"
            )
        for key, title in (("reproduce", "replay this run"), ("check", "run it and judge it as the grader did")):
            if r.get(key):  # not for a hidden world's run on a student's page
                rows.append(
                    f'<tr class="reproduce"><td colspan="6" title="{title}">'
                    f'<code class="cmd">{esc(r.get(key))}</code></td></tr>'
                )
    return (
        f"<h2>Runs that went wrong ({len(failed)} of {len(runs)})</h2>"
        '<table id="failed-runs"><thead><tr><th>Variant</th><th class="num">Seed</th><th>Ended</th>'
        '<th>Missed</th><th class="num">Time</th><th class="num">Collisions</th></tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table>"
    )


def outcome(node: dict[str, Any], never: set[str]) -> str:
    """What a node reached over all runs: ok, bad, mixed, running or never (see :data:`OUTCOMES`)."""
    ticks, success, failure = (num(node.get(k)) or 0 for k in ("ticks", "success", "failure"))
    if ticks <= 0 or node.get("path") in never:
        return "never"
    if success and failure:
        return "mixed"
    return "ok" if success else "bad" if failure else "running"


def tree_guides(depths: list[int]) -> list[str]:
    """The lines that draw a tree of nodes listed depth first (their ``depths``): each node's
    branch, and its ancestors' lines going on to their later siblings.

    >>> print("\\n".join(g + name for g, name in zip(tree_guides([0, 1, 2, 2, 1]), "root a a1 a2 b".split())))
    root
    ├─ a
    │  ├─ a1
    │  └─ a2
    └─ b
    """

    def last(i: int) -> bool:  # no later sibling: the next node as shallow comes up first, or none
        return next((d for d in depths[i + 1 :] if d <= depths[i]), -1) < depths[i]

    guides, open_lines = [], [False] * (max(depths, default=0) + 1)
    for i, depth in enumerate(depths):
        if depth == 0:
            guides.append("")
            continue
        line = "".join("│  " if open_lines[k] else "   " for k in range(1, depth))
        guides.append(line + ("└─ " if last(i) else "├─ "))
        open_lines[depth] = not last(i)
    return guides


def _coverage(student: dict[str, Any]) -> str:
    coverage = as_dict(student.get("coverage"))
    nodes = [as_dict(n) for n in as_list(coverage.get("nodes"))]
    if not nodes:
        return ""
    never = {str(p) for p in as_list(coverage.get("never_ticked"))}
    depths = [min(max(int(num(n.get("depth")) or str(n.get("path", "")).count("/")), 0), 30) for n in nodes]
    guides = tree_guides(depths)
    rows = []
    for node, guide in zip(nodes, guides, strict=True):
        kind = outcome(node, never)
        what = node.get("behaviour") or node.get("kind")
        what = "" if what == node.get("name") else what
        ended = ", ".join(
            f"{esc(child.rsplit('/', 1)[-1])} &times;{fmt(count)}"
            for child, count in as_dict(node.get("ended_by")).items()
            if isinstance(child, str)
        )
        ended_html = f'<div class="ended">ended by {ended}</div>' if ended else ""
        label = ' <span class="badge never">never ticked</span>' if kind == "never" else ""
        rows.append(
            f'<tr class="tree-node cov-{kind}" title="{esc(node.get("path"))}: {OUTCOMES[kind]}">'
            f'<td class="node"><span class="guide" aria-hidden="true">{guide}</span><span class="dot"></span>'
            f'{esc(node.get("name"))} <span class="kind">{esc(what)}</span>{label}{ended_html}</td>'
            + "".join(f'<td class="num">{fmt(node.get(k))}</td>' for k in ("ticks", "success", "failure", "running"))
            + f"<td class=where>{where_code(node.get('where'))}</td></tr>"
        )
    legend = "".join(
        f'<span class="cov-{k}"><span class="dot"></span>{esc(text)}</span>' for k, text in OUTCOMES.items()
    )
    untouched = len([r for r in rows if "cov-never" in r])
    return (
        f"<h2>The tree over {fmt(coverage.get('runs'))} runs</h2>"
        f'<p class="sub">{untouched} of {len(rows)} nodes never ticked.</p><div class="legend">{legend}</div>'
        '<table class="tree" id="coverage"><thead><tr><th>Node</th><th class="num">Ticks</th>'
        '<th class="num">Success</th><th class="num">Failure</th><th class="num">Running</th><th>Where</th>'
        f"</tr></thead><tbody>{''.join(rows)}</tbody></table>"
    )


def student_page(results: dict[str, Any], student: dict[str, Any], mazes: dict[str, Maze | str]) -> str:
    """The whole HTML page of ``student`` (one entry of results' ``students``)."""
    assignment = as_dict(results.get("assignment"))
    body = "".join(
        (
            _header(results, student),
            _messages(student),
            _criteria(student),
            _palette(student),
            _pictures(results, student, mazes),
            _failed_runs(student),
            _coverage(student),
        )
    )
    return shell(f"{student.get('name')} — {assignment.get('name') or 'grade'}", body)
