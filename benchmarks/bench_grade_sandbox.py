"""Benchmark: what confining students' plugins costs ``thymio-bt grade`` (issue 42).

Four ways to grade the same class of 60 submissions x 12 runs (the part 1-2 assignment, the four
kinds of ``examples/class/`` that run), measured in turns within one process so that a shared
machine's load falls on all of them alike; the ratios are the result:

- ``yaml``: the shipped assignment (no plugins): every tree ticks in the grader's worker;
- ``allowed``: the assignment with ``plugins: true``, the same YAML-only submissions (they run no
  code of the student's: their trees tick in the grader's workers, as with ``yaml``);
- ``plugins``: the assignment with ``plugins: true`` and each submission bringing a plugin file
  (a node its tree does not use): every tree ticks in a confined process of its own, one message
  each way per tick;
- ``always``: plugins allowed, YAML-only submissions, but confined anyway (``sandbox="always"``):
  what running YAML-only submissions outside too would cost.

Target: ``plugins`` within 1.5 x ``yaml``. Also the CPU seconds each way takes (every process of
the grade: on a machine of its own with enough processes at once, the wall time follows them), and
the cost of one tick's round trip on the wire (an observation out, a reply in, two processes).

Run: ``python benchmarks/bench_grade_sandbox.py [--students 60] [--rounds 2] [--ways yaml,plugins]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from _common import ROOT, save_results, table, verdict
from bench_grade import make_class

from thymio_bt.grade.grader import grade

TARGET = 1.5
PLUGIN = "from thymio_bt.behaviours import RobotBehaviour\nclass Unused(RobotBehaviour):\n    '''Not in the tree.'''\n"


def plugin_class(subs: list[Path]) -> None:
    """Give each submission a plugin file its mission names (the tree itself unchanged)."""
    for folder in subs:
        (folder / "helper.py").write_text(PLUGIN)
        mission = folder / "part1_2.yaml"
        mission.write_text("plugins: [helper.py]\n" + mission.read_text())


def plugin_assignment(folder: Path) -> Path:
    """The shipped part 1-2 assignment with plugins allowed (its mazes named by absolute paths)."""
    text = (ROOT / "assignments" / "course_part1_2.yaml").read_text()
    text = text.replace("plugins: false", "plugins: true").replace("maze: ../mazes/", f"maze: {ROOT}/mazes/")
    text = text.replace("maze: worlds/", f"maze: {ROOT}/assignments/worlds/")
    path = folder / "plugins.yaml"
    path.write_text(text)
    return path


def round_trip_us(n: int = 20000) -> float:
    """µs per tick's round trip on the wire: a typical observation out, a reply back (two processes),
    each written and read as the grader and a submission's process do (:mod:`thymio_bt.grade.wire`)."""
    import socket

    from thymio_bt.grade.wire import Link, observation_frame, read_observation, read_reply, reply_frame

    inf = float("inf")
    observation = (12.3, True, True, True, 0.4812, 0.1003, 0.0012, 0.071, 0.052, 0.049, 0.055, 0.073, inf, inf)
    observation += (0.1, 0.0, 0.1, 0.0, 0)
    ours, theirs = socket.socketpair()
    pid = os.fork()
    if pid == 0:
        ours.close()
        link = Link(theirs)
        for _ in range(n):
            read_observation(link.receive_frame(None))
            link.send_frame(reply_frame("RUNNING", [(0.1, 0.002)], {}))
        os._exit(0)
    theirs.close()
    link = Link(ours)
    began = time.perf_counter()
    for _ in range(n):
        link.send_frame(observation_frame(observation, []))
        read_reply(link.receive_frame(time.monotonic() + 5))
    elapsed = time.perf_counter() - began
    os.waitpid(pid, 0)
    return elapsed / n * 1e6


def _cpu_seconds() -> float:
    """User and system CPU seconds of this process and the children it waited for (the workers, the
    zygote and, through it, the submissions' processes)."""
    import resource

    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=60)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--ways", default="yaml,allowed,plugins,always", help="which ways, comma-separated")
    args = parser.parse_args()
    chosen = args.ways.split(",")
    workers = os.cpu_count() or 1
    os.chdir(ROOT)
    times: dict[str, list[float]] = {name: [] for name in chosen}
    cpu: dict[str, list[float]] = {name: [] for name in chosen}
    scores: dict[str, float | None] = {}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "y").mkdir()
        (root / "p").mkdir()
        yaml_subs = make_class(root / "y", args.students)
        plugin_subs = make_class(root / "p", args.students)
        plugin_class(plugin_subs)
        allowed = plugin_assignment(root)
        ways = {
            "yaml": lambda: grade("assignments/course_part1_2.yaml", yaml_subs, workers=workers, worlds=root / "w"),
            "allowed": lambda: grade(allowed, yaml_subs, workers=workers, worlds=root / "w"),
            "plugins": lambda: grade(allowed, plugin_subs, workers=workers, worlds=root / "w"),
            "always": lambda: grade(allowed, yaml_subs, workers=workers, worlds=root / "w", sandbox="always"),
        }
        for _ in range(args.rounds):
            for name in chosen:
                way = ways[name]
                began, used = time.perf_counter(), _cpu_seconds()
                results = way()
                times[name].append(time.perf_counter() - began)
                cpu[name].append(_cpu_seconds() - used)
                scores[name] = results.summary.mean_score
                print(f"{name}: {times[name][-1]:.2f} s, {results.summary.confinement}", flush=True)
    others = [name for name in chosen if name != "yaml"]
    ratios = {name: [t / y for t, y in zip(times[name], times["yaml"], strict=True)] for name in others}
    cpu_ratios = {name: [t / y for t, y in zip(cpu[name], cpu["yaml"], strict=True)] for name in others}
    wire = round_trip_us()
    rows = [(name, ", ".join(f"{t:.2f}" for t in samples)) for name, samples in times.items()]
    rows += [(f"{name} / yaml", ", ".join(f"{r:.2f}" for r in rs)) for name, rs in ratios.items()]
    rows += [(f"{name}, CPU s", ", ".join(f"{t:.1f}" for t in samples)) for name, samples in cpu.items()]
    rows += [(f"{name} / yaml, CPU", ", ".join(f"{r:.2f}" for r in rs)) for name, rs in cpu_ratios.items()]
    rows += [("tick round trip on the wire", f"{wire:.1f} µs"), ("workers", str(workers))]
    print(f"bench_grade_sandbox: {args.students} submissions x 12 runs, {args.rounds} rounds in turns")
    print(table(rows, ("measure", "value (s, each round)")))
    for name, rs in ratios.items():
        print(f"{name} / yaml: worst {max(rs):.2f} (target <= {TARGET:g}: {verdict(max(rs), TARGET, False)})")
    print(f"mean scores (the same class graded each way): {scores}")
    save_results(
        "grade_sandbox",
        {
            "students": args.students,
            "workers": workers,
            "seconds": {k: [round(t, 3) for t in v] for k, v in times.items()},
            "ratios": {k: [round(r, 3) for r in v] for k, v in ratios.items()},
            "cpu_seconds": {k: [round(t, 2) for t in v] for k, v in cpu.items()},
            "cpu_ratios": {k: [round(r, 3) for r in v] for k, v in cpu_ratios.items()},
            "round_trip_us": round(wire, 2),
            "mean_scores": scores,
            "target": TARGET,
        },
    )


if __name__ == "__main__":
    main()
