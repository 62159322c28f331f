"""The grade's results for other tools: a gradebook CSV (a row per student, a column per
criterion) and JUnit XML (a testsuite per student, a testcase per criterion: what GitLab, Jenkins
and classroom autograders read), and the summary table printed at the end.

Example::

    >>> from thymio_bt.grade.palette import Finding
    >>> from thymio_bt.grade.results import AssignmentInfo, CriterionInfo, CriterionScore, StudentResult, VariantScore
    >>> stops = CriterionInfo(name="stops", points=3.0, variants=["course", "hidden"])
    >>> ada = StudentResult(name="ada", file="ada/m.yaml", status="graded", score=0.5, max=3.0, penalty=-1.0,
    ...     palette=[Finding("forbid", "WallFollow", "ada/m.yaml:7", "WallFollow is not allowed", 1.0)],
    ...     criteria=[CriterionScore(name="stops", points=3.0, earned=1.5, runs=2, passed_runs=1,
    ...         feedback="stopped 7.0 cm from the wall", variants=[VariantScore(name="course", earned=1.5),
    ...         VariantScore(name="hidden")])])
    >>> results = ClassResults(assignment=AssignmentInfo(name="a", max=3.0, criteria=[stops]), students=[ada])
    >>> print(gradebook_csv(results), end="")
    student,status,score,max,stops,penalty,palette,stops @ course,stops @ hidden
    ada,graded,0.5,3,1.5,-1,WallFollow is not allowed (at ada/m.yaml:7; -1),1.5,0
    >>> print(junit_xml(results).splitlines()[1])
    <testsuites name="a" tests="2" failures="2" errors="0">
"""

from __future__ import annotations

import csv
import io
import xml.etree.ElementTree as ET
from typing import Any

from thymio_bt.grade.palette import Finding
from thymio_bt.grade.results import ClassResults, StudentResult, StudentStatus


def gradebook_csv(results: ClassResults) -> str:
    """One row per student: status, score, max, the points earned on each criterion, the palette's
    penalty (negative: the columns sum to the score) and its findings, then each criterion's points
    per variant (``NAME @ VARIANT``)."""
    criteria = results.assignment.criteria
    names = [c.name for c in criteria]
    per_variant = [(c.name, v) for c in criteria for v in c.variants]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(
        ["student", "status", "score", "max", *names, "penalty", "palette", *(f"{n} @ {v}" for n, v in per_variant)]
    )
    for student in results.students:
        earned = {c.name: c.earned for c in student.criteria}
        by_variant = {(c.name, v.name): v.earned for c in student.criteria for v in c.variants}
        findings = "; ".join(_finding(f) for f in student.palette)
        writer.writerow(
            [_cell(student.name), student.status.value, f"{student.score:g}", f"{student.max:g}"]
            + [f"{earned.get(n, 0.0):g}" for n in names]
            + [f"{student.penalty:g}", _cell(findings)]
            + [f"{by_variant.get(key, 0.0):g}" for key in per_variant]
        )
    return out.getvalue()


def _finding(finding: Finding) -> str:
    """A palette finding in one line: 'WallFollow is not allowed in this assignment (at m.yaml:13; -4)'."""
    at = f"at {finding.where}; " if finding.where else ""
    return f"{finding.message} ({at}-{finding.points:g})"


def _said(finding: dict[str, Any]) -> str:
    """:func:`_finding` of a finding as results.json (and so the Gradescope file) holds it."""
    return _finding(Finding(**finding))


def _cell(text: str) -> str:
    """A student's name as a spreadsheet shows it, never as a formula (CSV injection)."""
    return "'" + text if text[:1] in ("=", "+", "-", "@", "\t", "\r") else text


def junit_xml(results: ClassResults) -> str:
    """JUnit XML: a testsuite per student, a testcase per criterion (failed: its feedback) and one
    for the palette (failed: each rule broken and what it cost); an invalid submission's or a grader
    error's criteria are errors."""
    name = results.assignment.name
    root = ET.Element("testsuites", name=name)
    for student in results.students:
        suite = ET.SubElement(root, "testsuite", name=student.name, skipped="0")
        props = ET.SubElement(suite, "properties")
        status = student.status.value
        for key, value in (("status", status), ("score", student.score), ("max", student.max), ("file", student.file)):
            ET.SubElement(props, "property", name=key, value=str(value))
        for criterion in student.criteria:
            case = ET.SubElement(suite, "testcase", classname=f"{name}.{student.name}", name=criterion.name)
            if student.status != StudentStatus.GRADED:
                error = ET.SubElement(case, "error", message=f"submission {status}", type=status)
                error.text = "\n".join(student.messages)
            elif not criterion.passed:
                message = criterion.feedback or "failed"
                failure = ET.SubElement(case, "failure", message=message, type="criterion")
                failure.text = message + (f"\nat {criterion.where}" if criterion.where else "")
        _palette_case(suite, name, student)
    ET.indent(root)
    _count_cases(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _palette_case(suite: ET.Element, assignment: str, student: StudentResult) -> None:
    """The palette as a testcase of its own: failed with each finding and the points it cost."""
    findings = student.palette
    case = ET.SubElement(suite, "testcase", classname=f"{assignment}.{student.name}", name="palette")
    if findings:
        lost = sum(f.points for f in findings)
        failure = ET.SubElement(
            case, "failure", message=f"{len(findings)} palette rule(s) broken, -{lost:g} points", type="palette"
        )
        failure.text = "\n".join(_finding(f) for f in findings)


def _count_cases(root: ET.Element) -> None:
    """The counts of each testsuite and of the whole, from the testcases written."""
    totals = {"tests": 0, "failures": 0, "errors": 0}
    for suite in root.iter("testsuite"):
        cases = suite.findall("testcase")
        counts = {
            "tests": len(cases),
            "failures": sum(c.find("failure") is not None for c in cases),
            "errors": sum(c.find("error") is not None for c in cases),
        }
        for key, value in counts.items():
            suite.set(key, str(value))
            totals[key] += value
    for key, value in totals.items():
        root.set(key, str(value))


def summary_table(results: ClassResults) -> str:
    """The table printed at the end: each student's status and score, then each criterion's pass rate."""
    students = results.students
    width = max([7, *(len(s.name) for s in students)])
    lines = [f"{'student':<{width}}  {'status':<8} {'score':>7}"]
    for s in students:
        lines.append(f"{s.name:<{width}}  {s.status.value:<8} {s.score:>7g} / {s.max:g}")
    rates = [(c.name, c.pass_rate) for c in results.summary.criteria if c.pass_rate is not None]
    if rates:
        lines.append("")
        lines.append("criterion pass rate (graded students):")
        hardest = min(range(len(rates)), key=lambda i: rates[i][1])
        for i, (name, rate) in enumerate(rates):
            mark = "  <- most missed" if i == hardest and rate < 1 else ""
            lines.append(f"  {100 * rate:5.1f} %  {name}{mark}")
    return "\n".join(lines)


def gradescope_json(results: ClassResults) -> dict[str, Any]:
    """Gradescope's autograder results for the one student of ``results``: the score, and a test
    per criterion and visibility (its public variants' share ``visible``, its hidden ones'
    ``after_due_date``), each with the words students see (:func:`~.redact.for_students`), and a
    ``palette`` test for the penalty: Gradescope's JSON.

    >>> from thymio_bt.grade.results import AssignmentInfo, CriterionScore, StudentResult, VariantInfo, VariantScore
    >>> variants = [VariantInfo(name="course"), VariantInfo(name="box", visibility="hidden")]
    >>> stops = CriterionScore(name="stops", points=2.0, earned=1.0, feedback="...", where="m.yaml:10", variants=[
    ...     VariantScore(name="course", passed=True, earned=1.0),
    ...     VariantScore(name="box", feedback="stopped 7.0 cm from the wall")])
    >>> ada = StudentResult(name="ada", status="graded", score=1.0, max=2.0, criteria=[stops])
    >>> out = gradescope_json(ClassResults(assignment=AssignmentInfo(name="a", variants=variants), students=[ada]))
    >>> out["score"], [(t["name"], t["score"], t["max_score"], t["visibility"]) for t in out["tests"]]
    (1.0, [('stops', 1.0, 1.0, 'visible'), ('stops (hidden worlds)', 0.0, 1.0, 'after_due_date')])
    >>> out["tests"][1]["output"]
    'hidden world 1: stopped 7.0 cm from the wall (at m.yaml:10)'
    """
    from thymio_bt.grade.redact import for_students

    seen = for_students(results.to_json())
    (student,) = seen["students"]
    hidden = {v["name"] for v in seen["assignment"]["variants"] if v.get("visibility") == "hidden"}
    tests = [test for criterion in student["criteria"] for test in _criterion_tests(criterion, hidden)]
    if student.get("palette"):
        findings = "\n".join(_said(f) for f in student["palette"])
        tests.append(_test("palette", student.get("penalty", 0.0), 0.0, findings, "visible"))
    output = "\n".join(student["messages"]) if student["status"] != "graded" else ""
    return {"score": student["score"], "output": output or f"{student['score']:g} / {student['max']:g}", "tests": tests}


def _criterion_tests(criterion: dict[str, Any], hidden: set[str]) -> list[dict[str, Any]]:
    """A criterion's Gradescope tests: one for its public variants, one for its ``hidden`` ones
    (those it has); one for the whole criterion, saying why, when it was not graded."""
    variants = criterion.get("variants") or []
    if not variants:  # not graded: the whole criterion, and why
        return [
            _test(criterion["name"], criterion["earned"], criterion["points"], criterion.get("feedback"), "visible")
        ]
    share = criterion["points"] / len(variants)
    where = f" (at {criterion['where']})" if criterion.get("where") else ""
    tests = []
    for label, visibility, mine in (
        ("", "visible", [v for v in variants if v["name"] not in hidden]),
        (" (hidden worlds)", "after_due_date", [v for v in variants if v["name"] in hidden]),
    ):
        if mine:
            said = "\n".join(f"{v['name']}: {v['feedback']}{where}" for v in mine if not v["passed"])
            earned = sum(v["earned"] for v in mine)
            tests.append(_test(criterion["name"] + label, earned, share * len(mine), said or None, visibility))
    return tests


def _test(name: str, score: float, most: float, failed: str | None, visibility: str) -> dict[str, Any]:
    """One Gradescope test: failed (with what went wrong) when ``failed`` says something."""
    return {
        "name": name,
        "score": round(score, 3),
        "max_score": round(most, 3),
        "status": "failed" if failed else "passed",
        "output": failed or "",
        "visibility": visibility,
    }
