"""``thymio-bt grade --html DIR``: results.json as a static site a teaching assistant opens offline.

``DIR/index.html`` is the class: summary numbers, each criterion's pass rate as a bar (the one most
students miss highlighted), a table of the students linking to ``DIR/students/<name>.html``, one page
per student (:mod:`thymio_bt.grade.site_student`). Pages are self-contained (inline style and
SVG, no script, nothing fetched) and written atomically (:mod:`thymio_bt.outputs`). Student names
are untrusted: they are escaped in the pages and turned into safe file names, so ``../x`` or
``<script>`` stays text inside DIR.

Example:

>>> import tempfile
>>> out = Path(tempfile.mkdtemp())
>>> results = {"assignment": {"name": "a1", "max": 2, "criteria": [{"name": "stops", "points": 2}]},
...            "students": [{"name": "../../x", "status": "graded", "score": 2, "max": 2,
...                          "criteria": [{"name": "stops", "points": 2, "earned": 2, "passed": True}]}]}
>>> [str(p.relative_to(out)) for p in write_site(results, out)]
['index.html', 'students/x.html']
>>> page_names([{"name": "Zoë"}, {"name": "zoe"}, {"name": "<script>"}, {"name": ".."}])
['Zoe', 'zoe-2', 'script', 'student']
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from urllib.parse import quote

from thymio_bt.grade.site_page import as_dict, as_list, esc, fmt, num, safe_name, shell, status_badge
from thymio_bt.grade.site_replay import REPLAYS, write_replays
from thymio_bt.grade.site_student import run_failed, student_page
from thymio_bt.grade.site_svg import load_mazes
from thymio_bt.outputs import Output, make_folder

OPTION = "--html"
STUDENTS = "students"  # the folder of the student pages, inside DIR


def page_names(students: list[dict[str, Any]]) -> list[str]:
    """The page stem of each student, in order: :func:`safe_name`, made unique (ignoring case, for
    file systems that do) by a ``-2``, ``-3``... suffix."""
    taken: set[str] = set()
    names = []
    for student in students:
        stem = base = safe_name(as_dict(student).get("name"))
        n = 1
        while stem.casefold() in taken:
            n += 1
            stem = f"{base}-{n}"
        taken.add(stem.casefold())
        names.append(stem)
    return names


def criterion_stats(results: dict[str, Any]) -> list[dict[str, Any]]:
    """Per criterion of the assignment: how many graded students passed it, and how many runs did."""
    graded = [as_dict(s) for s in as_list(results.get("students")) if as_dict(s).get("status") == "graded"]
    names = [str(as_dict(c).get("name")) for c in as_list(as_dict(results.get("assignment")).get("criteria"))]
    for student in graded:  # a criterion only the students' results name still counts
        names += [str(as_dict(c).get("name")) for c in as_list(student.get("criteria"))]
    stats = []
    for name in dict.fromkeys(names):
        verdicts = [
            as_dict(c) for s in graded for c in as_list(s.get("criteria")) if str(as_dict(c).get("name")) == name
        ]
        runs = sum(num(c.get("runs")) or 0 for c in verdicts)
        stats.append(
            {
                "name": name,
                "points": next((as_dict(c).get("points") for c in verdicts), None),
                "students": len(graded),
                "passed": sum(c.get("passed") is True for c in verdicts),
                "run_rate": (sum(num(c.get("passed_runs")) or 0 for c in verdicts) / runs) if runs else None,
            }
        )
    return stats


def most_missed(stats: list[dict[str, Any]]) -> str | None:
    """The criterion most students miss (ties: the one fewest runs pass); None if nobody misses one."""
    missed = [s for s in stats if s["students"] and s["passed"] < s["students"]]
    if not missed:
        return None
    worst = min(missed, key=lambda s: (s["passed"] / s["students"], s["run_rate"] if s["run_rate"] is not None else 1))
    return str(worst["name"])


def _summary(results: dict[str, Any], students: list[dict[str, Any]]) -> str:
    summary = as_dict(results.get("summary"))
    maximum = as_dict(results.get("assignment")).get("max")
    count = {k: sum(s.get("status") == k for s in students) for k in ("graded", "invalid", "error")}
    graded_scores = [num(s.get("score")) for s in students if s.get("status") == "graded"]
    scores = [v for v in graded_scores if v is not None]
    mean = summary.get("mean_score", sum(scores) / len(scores) if scores else None)
    full = sum(1 for v in scores if num(maximum) is not None and v >= (num(maximum) or 0))
    runs = summary.get("runs", sum(len(as_list(s.get("runs"))) for s in students))
    failed = sum(run_failed(as_dict(r)) for s in students for r in as_list(s.get("runs")))
    cards = [
        (len(students), "students", f"{count['graded']} graded, {count['invalid']} invalid, {count['error']} error"),
        (f"{fmt(mean)} / {fmt(maximum)}", "mean score", "of the graded students"),
        (full, "full marks", f"of {count['graded']} graded"),
        (fmt(runs), "runs", f"{failed} went wrong; {fmt(summary.get('wall_time'), 1)} s of grading"),
    ]
    return (
        '<div class="cards" id="summary">'
        + "".join(
            f'<div class="card"><div class="big">{esc(big)}</div><div class="label">{esc(label)}</div>'
            f'<div class="label">{esc(more)}</div></div>'
            for big, label, more in cards
        )
        + "</div>"
    )


def _bars(stats: list[dict[str, Any]], worst: str | None) -> str:
    if not stats:
        return ""
    rows = []
    for s in stats:
        rate = s["passed"] / s["students"] if s["students"] else 0.0
        runs = f"; {s['run_rate']:.0%} of runs" if s["run_rate"] is not None else ""
        mark = s["name"] == worst
        rows.append(
            f'<div class="bar-row{" worst" if mark else ""}" data-criterion="{esc(s["name"])}" data-rate="{rate:.3f}">'
            f'<div class="name">{esc(s["name"])} <span class="muted">({fmt(s["points"])} pts)</span>'
            f"{'<span class=tag>most missed</span>' if mark else ''}</div>"
            f'<div class="bar" role="img" aria-label="{rate:.0%} passed">'
            f'<span style="width:{rate * 100:.1f}%"></span></div>'
            f'<div class="what">{s["passed"]} of {s["students"]} students{runs}</div></div>'
        )
    note = ""
    if worst is not None:
        s = next(s for s in stats if s["name"] == worst)
        note = (
            f'<p class="note bad" id="most-missed">Most missed: <strong>{esc(worst)}</strong>, '
            f"{s['students'] - s['passed']} of {s['students']} graded students lost its points.</p>"
        )
    else:
        note = '<p class="note" id="most-missed">Every graded student passed every criterion.</p>'
    return f'<h2>Criteria: who passed them</h2>{note}<div class="bars" id="criteria-bars">{"".join(rows)}</div>'


def _table(students: list[dict[str, Any]], stems: list[str], maximum: Any) -> str:
    rows = []
    for student, stem in zip(students, stems, strict=True):
        criteria = [as_dict(c) for c in as_list(student.get("criteria"))]
        passed = sum(c.get("passed") is True for c in criteria)
        runs = [as_dict(r) for r in as_list(student.get("runs"))]
        palette = len(as_list(student.get("palette")))
        href = quote(f"{STUDENTS}/{stem}.html")
        rows.append(
            f'<tr class="student"><td><a href="{esc(href)}">{esc(student.get("name"))}</a></td>'
            f"<td>{status_badge(student.get('status'))}</td>"
            f'<td class="num">{fmt(student.get("score"))} / {fmt(student.get("max", maximum))}</td>'
            f'<td class="num">{passed} / {len(criteria)}</td>'
            f'<td class="num">{sum(run_failed(r) for r in runs)} / {len(runs)}</td>'
            f'<td class="num">{palette or ""}</td></tr>'
        )
    return (
        '<h2>Students</h2><table id="students"><thead><tr><th>Student</th><th>Status</th>'
        '<th class="num">Score</th><th class="num">Criteria passed</th><th class="num">Runs gone wrong</th>'
        f'<th class="num">Forbidden nodes</th></tr></thead><tbody>{"".join(rows)}</tbody></table>'
    )


def _similar(results: dict[str, Any], students: list[dict[str, Any]], stems: list[str]) -> str:
    """The groups of students whose trees are the same up to names and values (the TA's to look at)."""
    groups = [as_list(g) for g in as_list(results.get("similar"))]
    if not groups:
        return ""
    page = {str(s.get("name")): stem for s, stem in zip(students, stems, strict=True)}
    items = "".join(
        "<li>"
        + ", ".join(
            f'<a href="{esc(quote(f"{STUDENTS}/{page[str(n)]}.html"))}">{esc(n)}</a>' if str(n) in page else esc(n)
            for n in group
        )
        + "</li>"
        for group in groups
    )
    return (
        '<h2>Similar trees</h2><p class="muted">The same tree up to node names, comments, formatting and '
        f'parameter values: worth a look, not a verdict.</p><ul id="similar">{items}</ul>'
    )


def class_page(results: dict[str, Any], students: list[dict[str, Any]], stems: list[str]) -> str:
    """The class page (``index.html``) linking to the student pages named ``stems``."""
    assignment = as_dict(results.get("assignment"))
    stats = criterion_stats(results)
    title = assignment.get("title") or assignment.get("name") or "assignment"
    body = (
        f"<h1>{esc(title)}</h1>"
        f'<p class="sub">assignment <code>{esc(assignment.get("name"))}</code> '
        + (f"from <code>{esc(assignment.get('file'))}</code>, " if assignment.get("file") else "")
        + f"out of {fmt(assignment.get('max'))} points</p>"
        + _summary(results, students)
        + _bars(stats, most_missed(stats))
        + _table(students, stems, assignment.get("max"))
        + _similar(results, students, stems)
    )
    return shell(f"{title} — class results", body)


def write_site(
    results: dict[str, Any],
    out_dir: Path,
    replays: dict[tuple[str, int], dict[str, Any]] | None = None,
    for_students: bool = False,
) -> list[Path]:
    """Write the class page and one page per student of ``results`` (results.json's content) into
    ``out_dir``, made if missing, with the failed runs' ``replays`` (:mod:`.site_replay`; none of a
    hidden variant ``for_students``); each file whole or not at all, and no page of an earlier grade
    left. The paths, the class page first."""
    out_dir = Path(out_dir)
    make_folder(out_dir, OPTION, "grade-site")
    make_folder(out_dir / STUDENTS, OPTION, "grade-site")
    students = [as_dict(s) for s in as_list(results.get("students"))]
    stems = page_names(students)
    mazes = load_mazes(as_dict(results.get("assignment")))
    replayed: list[Path] = []
    if replays:
        make_folder(out_dir / REPLAYS, OPTION, "grade-site")
        replayed = write_replays(results, replays, out_dir, stems, for_students)
    written = []
    for student, stem in zip(students, stems, strict=True):
        path = out_dir / STUDENTS / f"{stem}.html"
        Output(path, OPTION, stdout_ok=False).write_text(student_page(results, student, mazes))
        written.append(path)
    index = out_dir / "index.html"  # last: it links only pages that exist
    Output(index, OPTION, stdout_ok=False).write_text(class_page(results, students, stems))
    for stale in (out_dir / STUDENTS).glob("*.html"):  # a page of an earlier grade, linked from nowhere
        if stale not in written:
            stale.unlink()
    for stale in (out_dir / REPLAYS).glob("*.html"):  # an earlier grade's replay (a hidden one, perhaps)
        if stale not in replayed:
            stale.unlink()
    return [index, *written, *replayed]
