"""Physics + sensing alone (no behaviour tree): simulated seconds per wall second.

A long drive in the course maze (mazes/two_parts_maze.yaml) with a small reactive controller
written here: drive along the corridor (steering away from the closer side wall), and when the
front reads close, turn in place toward the side with more room until the front is clear again.
Commands at 10 Hz, ``sim.advance(0.1)`` per tick (10 x 100 Hz physics sub-steps and one 10 Hz
sensor refresh inside; each ray is cast when the controller first reads its sensor).

Measured:
  1. the whole loop (proximity -> controller -> drive -> advance(0.1)) for SIM_SECONDS,
     median of REPEATS -> real-time factor (target >= 2000x);
  2. where a tick's time goes, measured inside the same loop by wrapping the simulation's
     methods on the instance (µs per ``advance(0.1)``, per sensor refresh = pose + clearance
     bookkeeping, the ray queries of a tick, per C step; physics = advance - refresh), plus a bare
     step(0.01) timed in isolation, through the C function and through pymunk's public ``Space.step``;
  3. an untimed check run of the same (deterministic) drive that the robot really moves and
     never tunnels: it stays inside the maze box it started in, never crosses a wall's centre
     line between two ticks, and never overlaps a wall by more than PENETRATION_LIMIT.

Usage (from the repo root): python benchmarks/bench_sim.py [--seconds 120] [--repeats 5] [--spawn bonus]
"""

from __future__ import annotations

import argparse
import itertools
import math
import statistics
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pymunk

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import ROOT, median_time, per_call_us, save_results, table, verdict  # noqa: E402

from thymio_bt.backends.sim import Simulation  # noqa: E402
from thymio_bt.maze import load_maze  # noqa: E402
from thymio_bt.robot.interface import Pose  # noqa: E402
from thymio_bt.robot.model import COURSE  # noqa: E402

MAZE = ROOT / "mazes" / "two_parts_maze.yaml"
TICK = 0.1  # 10 Hz commands
TARGET_RTF = 2000.0
IDEAL_RTF = 2900.0  # docs/sources.md, "Performance baseline": physics + scans + trivial controller
PENETRATION_LIMIT = 0.005  # half a wall's thickness: deeper means the hull is past the centre line


class Reactive:
    """Corridor follower with a latched turn-in-place.

    Driving: 0.1 m/s, steering away from the closer of the two outer front rays (inf counts as
    the full range). When the closest of the three central front rays reads under TURN_AT, turn
    in place toward the side with more room, and keep turning until those three read clear.
    """

    CRUISE = 0.10
    TURN_RATE = 1.5
    TURN_AT = 0.035
    CLEAR_AT = 0.09
    GAIN = 8.0

    def __init__(self) -> None:
        self.turn = 0.0

    def __call__(self, scan) -> tuple[float, float]:
        r = COURSE.range_max
        left = min(scan["front_left"], r)
        cleft = min(scan["front_center_left"], r)
        centre = min(scan["front_center"], r)
        cright = min(scan["front_center_right"], r)
        right = min(scan["front_right"], r)
        ahead = min(cleft, centre, cright)
        if self.turn:
            if ahead >= self.CLEAR_AT:
                self.turn = 0.0
            else:
                return 0.0, self.turn
        if ahead < self.TURN_AT:
            self.turn = self.TURN_RATE if left + cleft >= right + cright else -self.TURN_RATE
            return 0.0, self.turn
        return self.CRUISE, self.GAIN * (left - right)


def make_sim(spawn: str) -> Simulation:
    maze = load_maze(MAZE)
    return Simulation(maze, spawn=maze.spawn(spawn))


def drive(sim: Simulation, ticks: int, on_tick=None) -> None:
    """The benchmarked loop: read, decide, command, advance."""
    ctrl = Reactive()
    proximity, command, advance = sim.proximity, sim.drive, sim.advance
    for _ in range(ticks):
        v, w = ctrl(proximity())
        command(v, w)
        advance(TICK)
        if on_tick is not None:
            on_tick()


# ------------------------------------------------------------------ validation (untimed)
def _segments_cross(p, q, a, b) -> bool:
    def orient(o, s, t):
        return (s[0] - o[0]) * (t[1] - o[1]) - (s[1] - o[1]) * (t[0] - o[0])

    d1, d2 = orient(a, b, p), orient(a, b, q)
    d3, d4 = orient(p, q, a), orient(p, q, b)
    return d1 * d2 < 0 and d3 * d4 < 0


def _penetration(sim: Simulation, pose: Pose) -> float:
    """Deepest overlap (m, >= 0) of the robot's hull at ``pose`` with any wall."""
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    hull = [(pose.x + x * c - y * s, pose.y + x * s + y * c) for x, y in COURSE.hull]
    probe = pymunk.Poly(pymunk.Body(body_type=pymunk.Body.STATIC), hull)
    probe.cache_bb()
    deepest = 0.0
    for hit in sim.space.shape_query(probe):
        if hit.shape.body is not sim.space.static_body:
            continue
        for point in hit.contact_point_set.points:
            deepest = max(deepest, -point.distance)
    return deepest


def check_drive(spawn: str, seconds: float) -> dict:
    """Replay the drive with per-tick bookkeeping; report motion and any tunnelling."""
    sim = make_sim(spawn)
    walls = [(w.start, w.end) for w in sim.maze.walls]
    start = sim.true_pose()
    # the maze box the robot starts in: the course maze has two, split at x = 0.7
    box = (0.0, 0.0, 0.6, 0.8) if start.x < 0.7 else (0.8, 0.0, 2.0, 0.8)
    poses = [start]
    stats = {"moving_ticks": 0, "turning_ticks": 0}

    def record():
        poses.append(sim.true_pose())
        cmd = sim.command()
        if cmd.linear:
            stats["moving_ticks"] += 1
        elif cmd.angular:
            stats["turning_ticks"] += 1

    ticks = round(seconds / TICK)
    drive(sim, ticks, record)
    crossings = sum(
        _segments_cross((p.x, p.y), (q.x, q.y), a, b) for p, q in itertools.pairwise(poses) for a, b in walls
    )
    outside = sum(not (box[0] < p.x < box[2] and box[1] < p.y < box[3]) for p in poses)
    deepest = max(_penetration(sim, p) for p in poses)
    path = sum(math.dist((p.x, p.y), (q.x, q.y)) for p, q in itertools.pairwise(poses))
    cells = {(int(p.x / 0.2), int(p.y / 0.2)) for p in poses}
    ok = crossings == 0 and outside == 0 and deepest <= PENETRATION_LIMIT
    return {
        "sim_time": sim.time(),
        "ticks": ticks,
        "path_m": round(path, 3),
        "cells_visited": len(cells),
        "moving_ticks": stats["moving_ticks"],
        "turning_ticks": stats["turning_ticks"],
        "collisions": len(sim.collisions),
        "wall_crossings": crossings,
        "poses_outside_box": outside,
        "max_penetration_m": round(deepest, 5),
        "no_tunnelling": ok,
        "final_pose": {k: round(v, 4) for k, v in sim.true_pose().as_dict().items()},
    }


# ------------------------------------------------------------------ cost breakdown
class _Timed:
    """Wraps a callable and accumulates its wall time (perf_counter around each call)."""

    def __init__(self, fn):
        self.fn, self.calls, self.total = fn, 0, 0.0

    def __call__(self, *args):
        t0 = perf_counter()
        out = self.fn(*args)
        self.total += perf_counter() - t0
        self.calls += 1
        return out

    def us(self) -> float:
        return self.total / self.calls * 1e6 if self.calls else 0.0


perf_counter = time.perf_counter


def breakdown(spawn: str, seconds: float, repeats: int) -> dict:
    """Where a tick's time goes, measured inside the real loop (same drive as the benchmark).

    The simulation's methods are wrapped on the instance only (nothing in thymio_bt is changed):
    ``advance``, ``drive``, ``_refresh_sensors`` (the 10 Hz sensor refresh: the pose and the
    clearance bookkeeping), ``_update_clearance`` (that bookkeeping alone), the ray reader (one ray
    query each, cast when the controller first reads that sensor) and the C step function (pymunk's,
    called through sim/fastpath.py).
    Each wrapper adds about 0.1 µs per call; the wrappers' own cost is measured and subtracted.
    Medians over ``repeats`` instrumented runs.
    """
    runs = []
    for _ in range(repeats):
        sim = make_sim(spawn)
        timed = {
            "advance": _Timed(sim.advance),
            "drive": _Timed(sim.drive),
            "refresh": _Timed(sim._refresh_sensors),
            "clearance": _Timed(sim._update_clearance),
            "ray": _Timed(sim._reader.read),
            "step": _Timed(sim._step[0]),
        }
        sim.advance, sim.drive = timed["advance"], timed["drive"]
        sim._refresh_sensors, sim._update_clearance = timed["refresh"], timed["clearance"]
        sim._reader, sim._step = (
            SimpleNamespace(names=sim._reader.names, read=timed["ray"]),
            (timed["step"], sim._step[1]),
        )
        t0 = perf_counter()
        drive(sim, round(seconds / TICK))
        ticks = timed["advance"].calls
        tick = (perf_counter() - t0) / ticks * 1e6
        runs.append(
            {k: t.us() for k, t in timed.items()}
            | {
                "steps_per_advance": timed["step"].calls / ticks,
                "rays_per_tick": timed["ray"].calls / ticks,
                "rays_us_per_tick": timed["ray"].total / ticks * 1e6,
                "tick": tick,
            }
        )
    # cost of one wrapper (two perf_counter calls + the call indirection)
    nop = _Timed(lambda *a: None)
    t0 = perf_counter()
    for _ in range(100000):
        nop()
    wrap = (perf_counter() - t0) / 100000 * 1e6
    med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
    steps = med["steps_per_advance"]
    # advance contains `steps` wrapped steps and one wrapped refresh (which contains one wrapped
    # clearance); the rays are cast when the loop's proximity() reads them, outside advance
    refresh = med["refresh"] - wrap
    clearance = med["clearance"]
    step = med["step"]
    advance = med["advance"] - wrap * (steps + 2)
    rays = med["rays_us_per_tick"] - wrap * med["rays_per_tick"]
    substep_python = (advance - refresh - steps * step) / steps

    # pymunk alone: a bare step(0.01) of the same space, robot in free space, velocity held; through
    # the C function as the simulation calls it, and through pymunk's public Space.step for scale
    sim = make_sim(spawn)
    sim.drive(0.0, 1.0)  # turning in place: no wall contact
    sim.advance(0.1)

    def steps_of(step, *handle):
        def steps_only(n):
            for _ in range(n):
                step(*handle, 0.01)

        return per_call_us(steps_only, 10000)[0]

    bare_step, public_step = steps_of(*sim._step), steps_of(sim.space.step)
    return {
        "advance_0.1_us": advance,
        "drive_us": med["drive"] - wrap,
        "sensor_refresh_us": refresh,
        "rays_us_per_tick": rays,
        "rays_per_tick": med["rays_per_tick"],
        "clearance_us": clearance,
        "space_step_in_loop_us": step,
        "substeps_per_advance": steps,
        "substep_python_overhead_us": substep_python,
        "physics_per_advance_us": advance - refresh,
        "bare_space_step_us": bare_step,
        "bare_public_space_step_us": public_step,
        "wrapper_overhead_us": wrap,
        "instrumented_tick_us": med["tick"],
        "instrumented_tick_less_wrappers_us": med["tick"] - wrap * (steps + 4),
    }


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="simulated seconds per run")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--spawn", default="bonus", help="a spawn of two_parts_maze (part1, part2, bonus)")
    args = ap.parse_args(argv)
    ticks = round(args.seconds / TICK)

    check = check_drive(args.spawn, args.seconds)

    sims: list[Simulation] = []

    def one_run():
        sim = make_sim(args.spawn)  # build is outside the timed loop below
        t0 = time.perf_counter()
        drive(sim, ticks)
        sims.append(sim)
        return time.perf_counter() - t0

    one_run()  # warm-up
    loop_s = [one_run() for _ in range(args.repeats)]
    loop = statistics.median(loop_s)
    sim_time = sims[-1].time()
    rtf = sim_time / loop
    load, _, maze = median_time(lambda: load_maze(MAZE), args.repeats)
    build, _, _ = median_time(lambda: Simulation(maze, spawn=maze.spawn(args.spawn)), args.repeats)
    m = breakdown(args.spawn, args.seconds, args.repeats)
    per_tick = loop / ticks * 1e6
    inst = m["instrumented_tick_less_wrappers_us"]
    rest = inst - m["advance_0.1_us"] - m["drive_us"] - m["rays_us_per_tick"]

    print(
        f"bench_sim: physics + sensing, no behaviour tree - {MAZE.name}, spawn '{args.spawn}', "
        f"{sim_time:.0f} s simulated, 10 Hz commands / 100 Hz physics, median of {args.repeats}"
    )
    print(
        f"drive check: path {check['path_m']} m, {check['cells_visited']} cells of 0.2 m visited, "
        f"{check['moving_ticks']} ticks forward / {check['turning_ticks']} turning in place, "
        f"{check['collisions']} wall contacts, max overlap {check['max_penetration_m'] * 1000:.2f} mm, "
        f"{check['wall_crossings']} wall crossings -> "
        f"{'no tunnelling' if check['no_tunnelling'] else 'TUNNELLING / ESCAPE DETECTED'}"
    )
    print()
    rows = [
        ("loop wall time", f"{loop * 1e3:.1f} ms", f"{ticks} ticks"),
        (
            "real-time factor",
            f"{rtf:.0f}x",
            f"target >= {TARGET_RTF:.0f}x: {verdict(rtf, TARGET_RTF)} (ideal loop in perf_baseline: ~{IDEAL_RTF:.0f}x)",
        ),
        ("per tick", f"{per_tick:.1f} us", "proximity + controller + drive + advance(0.1)"),
    ]
    print(table(rows, ("whole loop", "value", "note")))
    print()
    print(
        f"Where the time goes: the same drive with the simulation's methods wrapped by timers "
        f"(median of {args.repeats}; {inst:.1f} us per tick once the wrappers' own cost is removed, "
        f"against {per_tick:.1f} us unwrapped)"
    )
    share = lambda us: f"{us / inst * 100:.0f} %"  # noqa: E731
    steps = m["substeps_per_advance"]
    rows = [
        (
            "advance(0.1)",
            f"{m['advance_0.1_us']:.1f}",
            share(m["advance_0.1_us"]),
            f"{steps:.0f} sub-steps + 1 sensor refresh",
        ),
        (
            "  sensor refresh",
            f"{m['sensor_refresh_us']:.1f}",
            share(m["sensor_refresh_us"]),
            "per 10 Hz refresh: the pose and",
        ),
        ("    clearance tracking", f"{m['clearance_us']:.1f}", share(m["clearance_us"]), "min_clearance bookkeeping"),
        (
            "  physics (advance - refresh)",
            f"{m['physics_per_advance_us']:.1f}",
            share(m["physics_per_advance_us"]),
            f"= {m['physics_per_advance_us'] / steps:.2f} us per sub-step:",
        ),
        (
            "    C step(0.01) x10",
            f"{m['space_step_in_loop_us'] * steps:.1f}",
            share(m["space_step_in_loop_us"] * steps),
            f"{m['space_step_in_loop_us']:.2f} us each in the loop",
        ),
        (
            "    Python per sub-step x10",
            f"{m['substep_python_overhead_us'] * steps:.1f}",
            share(m["substep_python_overhead_us"] * steps),
            f"{m['substep_python_overhead_us']:.2f} us each (control-body update, counters)",
        ),
        (
            "ray queries",
            f"{m['rays_us_per_tick']:.1f}",
            share(m["rays_us_per_tick"]),
            f"{m['rays_per_tick']:.1f} a tick: each sensor cast when first read",
        ),
        ("drive(v, w)", f"{m['drive_us']:.1f}", share(m["drive_us"]), "wheel limits + seeding the body velocity"),
        ("controller + loop", f"{rest:.1f}", share(rest), "by difference"),
        ("bare C step(0.01), isolated", f"{m['bare_space_step_us']:.2f}", "", "pymunk alone, robot in free space"),
        (
            "bare Space.step(0.01), isolated",
            f"{m['bare_public_space_step_us']:.2f}",
            "",
            "the same through pymunk's public wrapper",
        ),
        ("load_maze(two_parts_maze)", f"{load * 1e6:.0f}", "", "once per run, not in the loop"),
        ("Simulation(maze, spawn)", f"{build * 1e6:.0f}", "", "once per run, not in the loop"),
    ]
    print(table(rows, ("per tick, in the loop", "us", "share", "note")))
    result = {
        "maze": MAZE.name,
        "spawn": args.spawn,
        "sim_seconds": sim_time,
        "ticks": ticks,
        "repeats": args.repeats,
        "loop_s_median": loop,
        "loop_s_samples": loop_s,
        "real_time_factor": rtf,
        "target_rtf": TARGET_RTF,
        "target_met": rtf >= TARGET_RTF,
        "us_per_tick": per_tick,
        "load_maze_s_median": load,
        "build_s_median": build,
        "breakdown_us": m,
        "drive_check": check,
    }
    save_results("sim", result)
    if not check["no_tunnelling"]:
        print("WARNING: the drive check failed; the timing above is not a valid benchmark.", file=sys.stderr)
    return result


if __name__ == "__main__":
    main()
