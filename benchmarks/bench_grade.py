"""Benchmark: ``thymio-bt grade`` of a class of 60 submissions on the part 1-2 assignment (12 runs each).

Target (issue #32): 60 submissions x 12 runs in <= 30 s wall on this 2-core machine, everything
included (reading the submissions, the palette, forking a child per student under its limits, the
runs, judging the criteria, coverage). The class mixes the five kinds of ``examples/class/``
(correct, blind odometry, forbidden WallFollow, stops at 7 cm; the invalid one left out, since it
makes no runs), so the runs are the ones a real class makes, failures included.

With ``--callgrind`` it also counts the instructions of one student's 12 runs in-process (the
work a child does), by difference between a process that grades one student and one that grades
three, so that imports and start-up cancel out.

Run: ``python benchmarks/bench_grade.py [--students 60] [--repeats 3] [--callgrind]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
from pathlib import Path

from _common import ROOT, median_time, save_results, table, verdict

from thymio_bt.grade.grader import grade

TARGET = 30.0
KINDS = ("ada", "bob", "chen", "dana")

ONE_STUDENT = """
import sys
from pathlib import Path
from thymio_bt.grade.assignment import load_assignment
from thymio_bt.grade.student import StudentTask, grade_runs
from thymio_bt.grade.worlds import make_worlds
path = Path("assignments/course_part1_2.yaml")
assignment = load_assignment(path)
worlds = make_worlds(assignment, path, Path(sys.argv[2]))
for _ in range(int(sys.argv[1])):
    task = StudentTask("s", "examples/class/ada/part1_2.yaml", worlds, assignment.criteria, time_limit=120)
    grade_runs(task, lambda message: None)
"""


def make_class(folder: Path, students: int) -> list[Path]:
    """``students`` folders, each a copy of one of the example kinds, in turn."""
    out = []
    for i in range(students):
        target = folder / f"s{i:03d}"
        target.mkdir()
        shutil.copy(ROOT / "examples" / "class" / KINDS[i % len(KINDS)] / "part1_2.yaml", target / "part1_2.yaml")
        out.append(target)
    return out


def callgrind_per_student() -> float:
    """Instructions of one student's 12 runs in one process (by difference of 3 and 1 students)."""
    import sys

    from bench_instructions import instructions

    with tempfile.TemporaryDirectory() as worlds:
        one = instructions([sys.executable, "-c", ONE_STUDENT, "1", worlds], ROOT)
        three = instructions([sys.executable, "-c", ONE_STUDENT, "3", worlds], ROOT)
    return (three - one) / 2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--callgrind", action="store_true")
    args = parser.parse_args()
    workers = os.cpu_count() or 1
    os.chdir(ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        subs = make_class(Path(tmp), args.students)
        wall, samples, results = median_time(
            lambda: grade("assignments/course_part1_2.yaml", subs, workers=workers, worlds=Path(tmp) / "w"),
            args.repeats,
        )
    summary = results.summary
    runs = summary.runs
    rows = [
        ("students x runs", f"{args.students} x 12 = {runs}"),
        ("workers", str(workers)),
        ("wall (median)", f"{wall:.2f} s ({', '.join(f'{s:.2f}' for s in samples)})"),
        ("runs per second", f"{runs / wall:.1f}"),
        ("mean score", f"{summary.mean_score or 0:.2f} / 10"),
    ]
    data = {
        "students": args.students,
        "runs": runs,
        "workers": workers,
        "wall_median": round(wall, 3),
        "samples": [round(s, 3) for s in samples],
        "target": TARGET,
        "met": wall <= TARGET,
    }
    if args.callgrind:
        per_student = callgrind_per_student()
        rows.append(("instructions per student (12 runs, in-process)", f"{per_student / 1e6:,.0f} M"))
        data["instructions_per_student"] = per_student
    print("bench_grade: thymio-bt grade assignments/course_part1_2.yaml on a generated class")
    print(table(rows, ("measure", "value")))
    print(f"wall time: {wall:.1f} s (target <= {TARGET:g} s: {verdict(wall, TARGET, higher_is_better=False)})")
    save_results("grade", data)


if __name__ == "__main__":
    main()
