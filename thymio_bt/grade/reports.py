"""The grade's results for other tools: a gradebook CSV (a row per student, a column per
criterion) and JUnit XML (a testsuite per student, a testcase per criterion: what GitLab, Jenkins
and classroom autograders read), and the summary table printed at the end.

Example::

    >>> results = {"assignment": {"name": "a", "max": 3.0, "criteria": [{"name": "stops", "points": 3.0}]},
    ...     "students": [{"name": "ada", "file": "ada/m.yaml", "status": "graded", "score": 3.0, "max": 3.0,
    ...                   "messages": [], "criteria": [{"name": "stops", "points": 3.0, "earned": 3.0,
    ...                   "passed": True, "runs": 2, "passed_runs": 2, "feedback": None, "where": None}]}]}
    >>> print(gradebook_csv(results), end="")
    student,status,score,max,stops
    ada,graded,3,3,3
    >>> print(junit_xml(results).splitlines()[1])
    <testsuites name="a" tests="1" failures="0" errors="0">
"""

from __future__ import annotations

import csv
import io
import xml.etree.ElementTree as ET
from typing import Any


def gradebook_csv(results: dict[str, Any]) -> str:
    """One row per student: status, score, max, then the points earned on each criterion."""
    names = [c["name"] for c in results["assignment"]["criteria"]]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["student", "status", "score", "max", *names])
    for student in results["students"]:
        earned = {c["name"]: c["earned"] for c in student["criteria"]}
        writer.writerow(
            [_cell(student["name"]), student["status"], f"{student['score']:g}", f"{student['max']:g}"]
            + [f"{earned.get(n, 0.0):g}" for n in names]
        )
    return out.getvalue()


def _cell(text: str) -> str:
    """A student's name as a spreadsheet shows it, never as a formula (CSV injection)."""
    return "'" + text if text[:1] in ("=", "+", "-", "@", "\t", "\r") else text


def junit_xml(results: dict[str, Any]) -> str:
    """JUnit XML: a testsuite per student, a testcase per criterion (failed: its feedback);
    an invalid submission's or a grader error's testcases are errors."""
    students = results["students"]
    criteria_count = sum(len(s["criteria"]) for s in students)
    failures = sum(not c["passed"] for s in students if s["status"] == "graded" for c in s["criteria"])
    errors = sum(len(s["criteria"]) for s in students if s["status"] != "graded")
    root = ET.Element(
        "testsuites",
        name=results["assignment"]["name"],
        tests=str(criteria_count),
        failures=str(failures),
        errors=str(errors),
    )
    for student in students:
        cases = student["criteria"]
        suite = ET.SubElement(
            root,
            "testsuite",
            name=student["name"],
            tests=str(len(cases)),
            failures=str(sum(not c["passed"] for c in cases) if student["status"] == "graded" else 0),
            errors=str(len(cases) if student["status"] != "graded" else 0),
            skipped="0",
        )
        props = ET.SubElement(suite, "properties")
        for key in ("status", "score", "max", "file"):
            ET.SubElement(props, "property", name=key, value=str(student[key]))
        for criterion in cases:
            case = ET.SubElement(
                suite,
                "testcase",
                classname=f"{results['assignment']['name']}.{student['name']}",
                name=criterion["name"],
            )
            if student["status"] != "graded":
                error = ET.SubElement(case, "error", message=f"submission {student['status']}", type=student["status"])
                error.text = "\n".join(student["messages"])
            elif not criterion["passed"]:
                message = criterion["feedback"] or "failed"
                failure = ET.SubElement(case, "failure", message=message, type="criterion")
                failure.text = message + (f"\nat {criterion['where']}" if criterion["where"] else "")
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def summary_table(results: dict[str, Any]) -> str:
    """The table printed at the end: each student's status and score, then each criterion's pass rate."""
    students = results["students"]
    width = max([7, *(len(s["name"]) for s in students)])
    lines = [f"{'student':<{width}}  {'status':<8} {'score':>7}"]
    for s in students:
        lines.append(f"{s['name']:<{width}}  {s['status']:<8} {s['score']:>7g} / {s['max']:g}")
    summary = results.get("summary", {})
    rates = [c for c in summary.get("criteria", []) if c["pass_rate"] is not None]
    if rates:
        lines.append("")
        lines.append("criterion pass rate (graded students):")
        hardest = min(rates, key=lambda c: c["pass_rate"])
        for c in rates:
            mark = "  <- most missed" if c is hardest and c["pass_rate"] < 1 else ""
            lines.append(f"  {100 * c['pass_rate']:5.1f} %  {c['name']}{mark}")
    return "\n".join(lines)
