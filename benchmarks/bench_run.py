"""Mission benchmarks: in-process run, whole process, and IR-SIM 2.12 on the same walls.

(a) ``missions/maze_part1_2.yaml`` in-process: ``load_mission``, ``Run(mission)`` (world + tree)
    and ``run()`` timed separately, median of REPEATS after one warm-up -> real-time factor
    = simulated seconds / run() wall seconds (target >= 3000x, issue #19).
(b) the whole process ``thymio-bt run missions/maze_part1_2.yaml --quiet`` (the venv's console
    script), median of PROCESS_RUNS after one warm-up (target <= 0.25 s), with the interpreter's
    own start-up and the import of ``thymio_bt.cli`` for scale, and ``python -X importtime``'s
    largest imports of the same command.
(c) IR-SIM 2.12 on the same maze walls (each wall box of mazes/two_parts_maze.yaml becomes a
    ``rectangle`` obstacle of the same size, or its centre line a ``linestring``), one ``diff``
    robot (circle r = 0.055) with a 7-beam ``lidar2d`` whose 5 middle beams point like the Thymio's
    5 front sensors (0, ±19°, ±38°; range 0.0975 beyond the body), ``step_time`` 0.1, headless
    (``irsim.make(world, headless=True, log_level="ERROR")``), for the same simulated time as (a).
    The mission's shape is imitated with bench_sim's reactive controller: drive from spawn part1
    until the wall, move the robot to spawn part2 (as the mission deletes and respawns it), then
    follow the corridors. Median of REPEATS runs per variant; the env build is timed apart. The
    runs alternate: each repeat runs the mission's run() in-process and then every variant once.
    Ratio = the alternated runs' RTF / IR-SIM's RTF (target >= 15x, against the fastest variant).

Results go to benchmarks/results.json (section "run"). IR-SIM is optional: ``pip install -e .[bench]``.
Usage (from the repo root): python benchmarks/bench_run.py [--repeats 5] [--process-runs 9] [--skip-irsim]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import itertools
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import ROOT, save_results, table, verdict, version  # noqa: E402

MISSION = ROOT / "missions" / "maze_part1_2.yaml"
MAZE = ROOT / "mazes" / "two_parts_maze.yaml"
#: issue #19's targets (the earlier issues asked for 800x, 0.5 s and 8x)
TARGET_RTF = 3000.0
TARGET_PROCESS_S = 0.25
TARGET_RATIO = 15.0
ROBOT_R = 0.055


# ------------------------------------------------------------------ (a) in-process
def bench_in_process(repeats: int) -> dict:
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    def once():
        t0 = time.perf_counter()
        mission = load_mission(MISSION)
        t1 = time.perf_counter()
        run = Run(mission)
        t2 = time.perf_counter()
        result = run.run()
        t3 = time.perf_counter()
        return {
            "load_s": t1 - t0,
            "build_s": t2 - t1,
            "run_s": t3 - t2,
            "status": result.status,
            "sim_time": result.sim_time,
            "ticks": result.ticks,
            "collisions": result.collisions,
            "run_wall_time_reported": result.wall_time,
            "path_m": sum(
                math.dist(p[1:3], q[1:3]) for p, q in itertools.pairwise(result.trajectory) if q[0] - p[0] < 0.15
            ),
        }  # a respawn shows as a jump of one tick

    once()  # warm-up: first-call imports and caches
    runs = [once() for _ in range(repeats)]
    med = {k: statistics.median(r[k] for r in runs) for k in ("load_s", "build_s", "run_s")}
    sim_time = runs[0]["sim_time"]
    total = med["load_s"] + med["build_s"] + med["run_s"]
    return {
        "mission": MISSION.name,
        "status": runs[0]["status"],
        "sim_time": sim_time,
        "ticks": runs[0]["ticks"],
        "collisions": runs[0]["collisions"],
        "repeats": repeats,
        "path_m": round(runs[0]["path_m"], 3),
        **{f"{k}_median": v for k, v in med.items()},
        "total_s_median": total,
        "run_s_samples": [r["run_s"] for r in runs],
        "us_per_tick": med["run_s"] / runs[0]["ticks"] * 1e6,
        "real_time_factor": sim_time / med["run_s"],
        "real_time_factor_incl_load_build": sim_time / total,
        "target_rtf": TARGET_RTF,
        "target_met": sim_time / med["run_s"] >= TARGET_RTF,
    }


def breakdown_in_process(repeats: int) -> dict:
    """Where run()'s time goes: the same run with the runner's tree tick and the simulation's
    methods wrapped by timers (on the instances, and the runner module's ``tick`` for the run's
    length; nothing in thymio_bt's files is changed); µs per tick, medians."""
    from bench_sim import _Timed

    from thymio_bt.mission import load_mission
    from thymio_bt.run import runner
    from thymio_bt.run.runner import Run

    mission = load_mission(MISSION)
    expected = Run(mission).run()
    runs = []
    for _ in range(repeats + 1):
        run = Run(mission)
        sim = run.backend
        timed = {
            "tree.tick": _Timed(runner.tick),
            "advance": _Timed(sim.advance),
            "sensor refresh": _Timed(sim._refresh_sensors),
            "clearance": _Timed(sim._update_clearance),
            "rays": _Timed(sim._reader.read),
            "space.step": _Timed(sim._step[0]),
        }
        sim.advance = timed["advance"]
        sim._refresh_sensors, sim._update_clearance = timed["sensor refresh"], timed["clearance"]
        sim._reader, sim._step = (
            SimpleNamespace(names=sim._reader.names, read=timed["rays"]),
            (timed["space.step"], sim._step[1]),
        )
        runner.tick = timed["tree.tick"]
        try:
            t0 = time.perf_counter()
            result = run.run()
            total = time.perf_counter() - t0
        finally:
            runner.tick = timed["tree.tick"].fn
        ticks = result.ticks
        assert (result.status, ticks) == (expected.status, expected.ticks), (
            f"the timed run is not the mission's run: {result.status} after {ticks} ticks"
        )
        runs.append(
            {
                "tick_total": total / ticks * 1e6,
                **{k: t.total / ticks * 1e6 for k, t in timed.items()},
                "calls": {k: t.calls for k, t in timed.items()},
            }
        )
    runs = runs[1:]
    out = {k: statistics.median(r[k] for r in runs) for k in runs[0] if k != "calls"}
    out["calls"] = runs[0]["calls"]
    return out


# ------------------------------------------------------------------ (b) whole process
def cli_command() -> list[str]:
    script = Path(sys.executable).with_name("thymio-bt")
    head = [str(script)] if script.exists() else [sys.executable, "-m", "thymio_bt.cli"]
    return [*head, "run", str(MISSION.relative_to(ROOT)), "--quiet"]


def process_env(bytecode_cache: bool, cache_dir: str) -> dict[str, str]:
    """The environment for the timed processes.

    With ``bytecode_cache`` (Python's default behaviour) the .pyc files go to ``cache_dir`` through
    PYTHONPYCACHEPREFIX, so the benchmark writes nothing into the source tree; without it,
    PYTHONDONTWRITEBYTECODE=1 makes every process compile thymio_bt's sources again (site-packages
    keep the .pyc files pip wrote). Some shells and CI set that variable.
    """
    env = dict(os.environ)
    env.pop("PYTHONPYCACHEPREFIX", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if bytecode_cache:
        env["PYTHONPYCACHEPREFIX"] = cache_dir
    else:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


@contextlib.contextmanager
def _pycache_aside(package: Path):
    """Move ``package``'s __pycache__ directories aside meanwhile: PYTHONDONTWRITEBYTECODE only stops
    writing .pyc files, and a checkout that has them would be timed with them."""
    moved = []
    try:
        for cache in sorted(package.rglob("__pycache__")):
            aside = cache.with_name("__pycache__.bench-aside")
            cache.rename(aside)
            moved.append((aside, cache))
        yield
    finally:
        for aside, cache in moved:
            if cache.exists():
                shutil.rmtree(aside, ignore_errors=True)
            else:
                aside.rename(cache)


def time_process(cmd: list[str], runs: int, env: dict[str, str] | None = None) -> tuple[float, list[float]]:
    def once() -> float:
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, env=env)
        elapsed = time.perf_counter() - t0
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} exited {proc.returncode}: {proc.stderr.decode()[-2000:]}")
        return elapsed

    once()  # warm-up (file cache; fills the bytecode cache when there is one)
    samples = [once() for _ in range(runs)]
    return statistics.median(samples), samples


def import_offenders(env: dict[str, str], top: int = 8) -> dict:
    """``python -X importtime`` of the same command (one run): import time by package (self times
    summed over each top-level package's modules) and the slowest thymio_bt modules (self time)."""
    cmd = [sys.executable, "-X", "importtime", "-m", "thymio_bt.cli", *cli_command()[-3:]]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    by_package: dict[str, float] = {}
    own: list[tuple[str, float, float]] = []
    for line in proc.stderr.splitlines():
        m = re.match(r"import time:\s+(\d+) \|\s+(\d+) \|\s*(\S+)", line)
        if not m:
            continue
        self_ms, cumulative_ms, module = int(m.group(1)) / 1000, int(m.group(2)) / 1000, m.group(3)
        root = module.split(".")[0]
        by_package[root] = by_package.get(root, 0.0) + self_ms
        if root == "thymio_bt":
            own.append((module, self_ms, cumulative_ms))
    packages = sorted(by_package.items(), key=lambda kv: -kv[1])
    own.sort(key=lambda r: -r[1])
    return {
        "total_ms": round(sum(by_package.values()), 1),
        "by_package_self_ms": [{"package": k, "self_ms": round(v, 1)} for k, v in packages[:top]],
        "thymio_bt_modules": [
            {"module": m, "self_ms": round(s, 1), "cumulative_ms": round(c, 1)} for m, s, c in own[:5]
        ],
    }


def bench_process(runs: int) -> dict:
    cmd = cli_command()
    with tempfile.TemporaryDirectory(prefix="bench_pycache_") as cache:
        env = process_env(True, cache)
        whole, samples = time_process(cmd, runs, env)
        bare, _ = time_process([sys.executable, "-c", "pass"], runs, env)
        imports, _ = time_process([sys.executable, "-c", "import thymio_bt.cli"], runs, env)
        run_imports, _ = time_process(
            [sys.executable, "-c", "import thymio_bt.cli, thymio_bt.run.runner, thymio_bt.mission"], runs, env
        )
        offenders = import_offenders(env)
    with _pycache_aside(ROOT / "thymio_bt"):
        no_cache, no_cache_samples = time_process(cmd, runs, process_env(False, ""))
    worst = max(whole, no_cache)
    return {
        "command": " ".join(["thymio-bt", *cmd[-3:]]),
        "runs": runs,
        "median_s": whole,
        "samples_s": samples,
        "median_s_no_bytecode_cache": no_cache,
        "samples_s_no_bytecode_cache": no_cache_samples,
        "python_startup_s": bare,
        "import_cli_s": imports,
        "import_cli_runner_mission_s": run_imports,
        "target_s": TARGET_PROCESS_S,
        "target_met": worst <= TARGET_PROCESS_S,
        "importtime_top": offenders,
    }


# ------------------------------------------------------------------ (c) IR-SIM
def irsim_world(path: Path, shape: str, collision_mode: str, start) -> None:
    """Write an IR-SIM world YAML with the maze's walls and a Thymio-sized diff robot."""
    from thymio_bt.maze import load_maze
    from thymio_bt.robot.model import COURSE

    maze = load_maze(MAZE)
    xmin, ymin, xmax, ymax = maze.bounds()
    step = COURSE.sensors[1].yaw  # 0.33161 rad between neighbouring front sensors
    lines = [
        "world:",
        f"  width: {xmax - xmin + 0.1:.4f}",
        f"  height: {ymax - ymin + 0.1:.4f}",
        f"  offset: [{xmin - 0.05:.4f}, {ymin - 0.05:.4f}]",
        "  step_time: 0.1",
        "  sample_time: 0.1",
        f"  collision_mode: {collision_mode}",
        "  control_mode: auto",
        "",
        "robot:",
        "  - kinematics: {name: diff}",
        f"    shape: {{name: circle, radius: {ROBOT_R}}}",
        f"    state: [{start.x}, {start.y}, {start.yaw}]",
        "    vel_min: [-0.2, -4.0]",
        "    vel_max: [0.2, 4.0]",
        "    plot: {show_trajectory: false}",
        "    sensors:",
        "      - name: lidar2d",
        "        range_min: 0.0",
        f"        range_max: {COURSE.range_max + ROBOT_R}",
        f"        angle_range: {6 * step:.6f}",  # beams at 0, ±19, ±38, ±57 degrees
        "        number: 7",
        "        noise: false",
        "",
        "obstacle:",
    ]
    for wall in maze.walls:
        (x0, y0), (x1, y1) = wall.start, wall.end
        if shape == "linestring":
            lines.append(f"  - shape: {{name: linestring, vertices: [[{x0}, {y0}], [{x1}, {y1}]]}}")
            lines.append("    state: [0, 0, 0]")
        else:  # the same box as the pymunk wall: length + thickness long, thickness wide
            lines.append(
                f"  - shape: {{name: rectangle, length: {wall.length + wall.thickness:.6f}, width: {wall.thickness}}}"
            )
            lines.append(f"    state: [{(x0 + x1) / 2:.6f}, {(y0 + y1) / 2:.6f}, {math.atan2(y1 - y0, x1 - x0):.6f}]")
    path.write_text("\n".join(lines) + "\n")


def import_irsim():
    """Import IR-SIM quietly (it prints matplotlib back-end fallbacks to stdout on a headless box)."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    with contextlib.redirect_stdout(io.StringIO()):
        import irsim
    return irsim


def irsim_mission(irsim, world: Path, sim_time: float, part2) -> dict:
    from bench_sim import Reactive

    t0 = time.perf_counter()
    env = irsim.make(str(world), headless=True, log_level="ERROR")
    build = time.perf_counter() - t0
    steps = round(sim_time / env.step_time)
    ctrl = Reactive()
    inf = math.inf
    limit = ROBOT_R + 0.0975 - 1e-6
    phase1 = True
    collided = 0
    path = 0.0
    t0 = time.perf_counter()
    for _ in range(steps):
        r = env.get_lidar_scan()["ranges"]
        # beams right to left: index 1..5 = front_right .. front_left, 0 and 6 the two extra
        scan = {
            "front_right": r[1] - ROBOT_R if r[1] < limit else inf,
            "front_center_right": r[2] - ROBOT_R if r[2] < limit else inf,
            "front_center": r[3] - ROBOT_R if r[3] < limit else inf,
            "front_center_left": r[4] - ROBOT_R if r[4] < limit else inf,
            "front_left": r[5] - ROBOT_R if r[5] < limit else inf,
        }
        v, w = ctrl(scan)
        if phase1 and w:  # part 1 reached its wall: respawn at part 2
            env.robot.set_state([part2.x, part2.y, part2.yaw])
            ctrl, phase1, v, w = Reactive(), False, 0.0, 0.0
        env.step([v, w])
        path += abs(v) * 0.1
        collided += bool(env.robot.collision)
    run = time.perf_counter() - t0
    state = [round(float(v), 4) for v in env.robot.state.ravel()[:3]]
    env.end(ending_time=0)
    return {
        "build_s": build,
        "run_s": run,
        "steps": steps,
        "sim_time": steps * env.step_time,
        "collision_steps": collided,
        "final_state": state,
        "path_m": round(path, 3),
        "respawned": not phase1,
    }


VARIANTS = {  # name: (wall shape, collision mode)
    "rectangles, stop": ("rectangle", "stop"),
    "linestrings, stop": ("linestring", "stop"),
    "rectangles, contact": ("rectangle", "contact"),
}


def thymio_bt_run_s() -> float:
    """One in-process run() of the mission (Run built first, untimed), in seconds."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    run = Run(load_mission(MISSION))
    t0 = time.perf_counter()
    run.run()
    return time.perf_counter() - t0


def bench_irsim(sim_time: float, repeats: int) -> dict:
    """IR-SIM's variants and thymio-bt's run, alternated: each repeat runs thymio-bt once and each
    variant once, so a machine that slows down or speeds up during the benchmark moves both."""
    from thymio_bt.maze import load_maze

    t0 = time.perf_counter()
    irsim = import_irsim()
    import_s = time.perf_counter() - t0
    maze = load_maze(MAZE)
    start, part2 = maze.spawn("part1"), maze.spawn("part2")
    out = {
        "irsim_version": getattr(irsim, "__version__", version("ir-sim")),
        "import_s_in_process": import_s,
        "sim_time": sim_time,
        "robot": f"diff, circle r=0.055, lidar2d 7 beams over +-57 deg, range {0.0975 + ROBOT_R:.4f} from the centre",
        "step_time": 0.1,
        "variants": {},
    }
    with tempfile.TemporaryDirectory(prefix="bench_irsim_") as tmp:
        worlds = {}
        for name, (shape, mode) in VARIANTS.items():
            worlds[name] = Path(tmp) / f"world_{shape}_{mode}.yaml"
            irsim_world(worlds[name], shape, mode, start)
            irsim_mission(irsim, worlds[name], sim_time, part2)  # warm-up
        thymio_bt_run_s()  # warm-up
        samples: dict[str, list[dict]] = {name: [] for name in VARIANTS}
        ours = []
        for _ in range(repeats):
            ours.append(thymio_bt_run_s())
            for name, world in worlds.items():
                samples[name].append(irsim_mission(irsim, world, sim_time, part2))
        out["thymio_bt_alternated"] = {
            "run_s_median": statistics.median(ours),
            "run_s_samples": ours,
            "real_time_factor": sim_time / statistics.median(ours),
        }
        for name, (shape, mode) in VARIANTS.items():
            runs = samples[name]
            run_s = statistics.median(r["run_s"] for r in runs)
            out["variants"][name] = {
                "wall_shape": shape,
                "collision_mode": mode,
                "repeats": repeats,
                "run_s_median": run_s,
                "run_s_samples": [r["run_s"] for r in runs],
                "build_s_median": statistics.median(r["build_s"] for r in runs),
                "us_per_step": run_s / runs[0]["steps"] * 1e6,
                "steps": runs[0]["steps"],
                "real_time_factor": runs[0]["sim_time"] / run_s,
                "collision_steps": runs[0]["collision_steps"],
                "final_state": runs[0]["final_state"],
                "path_m": runs[0]["path_m"],
                "respawned": runs[0]["respawned"],
            }
    return out


# ------------------------------------------------------------------ main
def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--process-runs", type=int, default=9)
    ap.add_argument("--skip-irsim", action="store_true")
    args = ap.parse_args(argv)
    os.chdir(ROOT)

    a = bench_in_process(args.repeats)
    print(
        f"(a) {MISSION.name} in-process: {a['status']}, {a['sim_time']:.1f} s simulated, {a['ticks']} ticks, "
        f"{a['collisions']} collisions; median of {args.repeats} after a warm-up"
    )
    rows = [
        ("load_mission", f"{a['load_s_median'] * 1e3:.2f} ms", ""),
        ("Run(mission): world + tree", f"{a['build_s_median'] * 1e3:.2f} ms", ""),
        ("run()", f"{a['run_s_median'] * 1e3:.2f} ms", f"{a['us_per_tick']:.1f} us per tick"),
        (
            "real-time factor (run only)",
            f"{a['real_time_factor']:.0f}x",
            f"target >= {TARGET_RTF:.0f}x: {verdict(a['real_time_factor'], TARGET_RTF)}",
        ),
        ("real-time factor (load+build+run)", f"{a['real_time_factor_incl_load_build']:.0f}x", ""),
    ]
    print(table(rows, ("step", "median", "note")))
    d = breakdown_in_process(args.repeats)
    a["breakdown_us_per_tick"] = d
    tot = d["tick_total"]
    print(
        f"    where run()'s time goes (timers wrapped around the tree tick and the simulation's methods; "
        f"{tot:.1f} us per tick with the timers):"
    )
    rows = [
        (
            "root.tick() (py_trees + behaviours + drive())",
            f"{d['tree.tick']:.1f}",
            f"{d['tree.tick'] / tot * 100:.0f} %",
        ),
        (
            "  rays, each cast when a behaviour first reads its sensor",
            f"{d['rays']:.1f}",
            f"{d['rays'] / tot * 100:.0f} %",
        ),
        ("sim.advance(0.1)", f"{d['advance']:.1f}", f"{d['advance'] / tot * 100:.0f} %"),
        (
            "  sensor refresh (pose + clearance)",
            f"{d['sensor refresh']:.1f}",
            f"{d['sensor refresh'] / tot * 100:.0f} %",
        ),
        ("    of which clearance tracking", f"{d['clearance']:.1f}", f"{d['clearance'] / tot * 100:.0f} %"),
        ("  C step(0.01) x10 (sim/fastpath.py)", f"{d['space.step']:.1f}", f"{d['space.step'] / tot * 100:.0f} %"),
        (
            "  the rest of advance (sub-step Python, timers)",
            f"{d['advance'] - d['sensor refresh'] - d['space.step']:.1f}",
            f"{(d['advance'] - d['sensor refresh'] - d['space.step']) / tot * 100:.0f} %",
        ),
        (
            "run loop: events, trajectory, checks",
            f"{tot - d['tree.tick'] - d['advance']:.1f}",
            f"{(tot - d['tree.tick'] - d['advance']) / tot * 100:.0f} %",
        ),
    ]
    print(table(rows, ("per tick", "us", "share")))
    print()

    b = bench_process(args.process_runs)
    print(
        f"(b) whole process: {b['command']}; median of {args.process_runs} after a warm-up; "
        f".pyc files cached (in a temp dir) unless said otherwise"
    )
    nc = b["median_s_no_bytecode_cache"]
    rows = [
        (
            "thymio-bt run ... --quiet",
            f"{b['median_s'] * 1e3:.0f} ms",
            f"target <= {TARGET_PROCESS_S * 1e3:.0f} ms: {verdict(b['median_s'], TARGET_PROCESS_S, False)}",
        ),
        (
            "  same, PYTHONDONTWRITEBYTECODE=1",
            f"{nc * 1e3:.0f} ms",
            f"thymio_bt recompiled each run: {verdict(nc, TARGET_PROCESS_S, False)}",
        ),
        ("  python -c pass", f"{b['python_startup_s'] * 1e3:.0f} ms", "interpreter start-up"),
        ("  python -c 'import thymio_bt.cli'", f"{b['import_cli_s'] * 1e3:.0f} ms", "incl. start-up"),
        (
            "  + import thymio_bt.run.runner, .mission",
            f"{b['import_cli_runner_mission_s'] * 1e3:.0f} ms",
            "incl. start-up: what `run` imports",
        ),
    ]
    print(table(rows, ("process", "median", "note")))
    imp = b["importtime_top"]
    print(
        f"    python -X importtime of that command (one run; the tool inflates times): {imp['total_ms']:.0f} ms "
        f"of imports in all.\n    By package (self time summed):"
    )
    print(
        table(
            [("    " + r["package"], f"{r['self_ms']:.1f}") for r in imp["by_package_self_ms"]], ("    package", "ms")
        )
    )
    print("    Slowest thymio_bt modules (their own top-level code, e.g. building pydantic models):")
    print(
        table(
            [
                ("    " + r["module"], f"{r['self_ms']:.1f}", f"{r['cumulative_ms']:.1f}")
                for r in imp["thymio_bt_modules"]
            ],
            ("    module", "self ms", "cumulative ms"),
        )
    )
    print()

    result = {"in_process": a, "process": b}
    if args.skip_irsim or version("ir-sim") is None:
        print("(c) IR-SIM skipped" + ("" if args.skip_irsim else ": not installed (pip install -e .[bench])"))
    else:
        c = bench_irsim(a["sim_time"], args.repeats)
        result["irsim"] = c
        ours = c["thymio_bt_alternated"]
        print(
            f"(c) IR-SIM {c['irsim_version']} on the same walls, {a['sim_time']:.1f} s simulated at step_time 0.1, "
            f"headless; median of {args.repeats} after a warm-up, each repeat running thymio-bt's run() and "
            f"every variant once, in turn"
        )
        rows = []
        for name, v in c["variants"].items():
            ratio = ours["real_time_factor"] / v["real_time_factor"]
            v["ratio_thymio_bt_over_irsim"] = ratio
            rows.append(
                (
                    name,
                    f"{v['run_s_median'] * 1e3:.1f} ms",
                    f"{v['us_per_step']:.0f} us",
                    f"{v['real_time_factor']:.0f}x",
                    f"{ratio:.1f}x",
                    f"{v['build_s_median'] * 1e3:.0f} ms",
                    str(v["collision_steps"]),
                    f"{v['path_m']:.2f} m",
                )
            )
        rows.append(
            (
                "thymio-bt in-process",
                f"{ours['run_s_median'] * 1e3:.1f} ms",
                f"{ours['run_s_median'] / a['ticks'] * 1e6:.0f} us",
                f"{ours['real_time_factor']:.0f}x",
                "1.0x",
                f"{(a['load_s_median'] + a['build_s_median']) * 1e3:.0f} ms",
                str(a["collisions"]),
                f"{a['path_m']:.2f} m",
            )
        )
        print(
            table(rows, ("simulator", "run", "per step", "RTF", "thymio-bt faster by", "build", "collisions", "driven"))
        )
        fastest = max(c["variants"].values(), key=lambda v: v["real_time_factor"])
        ratio = ours["real_time_factor"] / fastest["real_time_factor"]
        c["ratio_vs_fastest_variant"] = ratio
        c["target_ratio"] = TARGET_RATIO
        c["target_met"] = ratio >= TARGET_RATIO
        print(
            f"    ratio against the fastest IR-SIM variant: {ratio:.1f}x "
            f"(target >= {TARGET_RATIO:.0f}x: {verdict(ratio, TARGET_RATIO)})"
        )
    print("\nsummary")
    rows = [
        (
            "(a) in-process mission RTF",
            f"{a['real_time_factor']:.0f}x",
            f">= {TARGET_RTF:.0f}x",
            verdict(a["real_time_factor"], TARGET_RTF),
        ),
        (
            "(b) whole process",
            f"{b['median_s']:.3f} s",
            f"<= {TARGET_PROCESS_S} s",
            verdict(b["median_s"], TARGET_PROCESS_S, False),
        ),
        (
            "(b) same, without .pyc cache",
            f"{b['median_s_no_bytecode_cache']:.3f} s",
            f"<= {TARGET_PROCESS_S} s",
            verdict(b["median_s_no_bytecode_cache"], TARGET_PROCESS_S, False),
        ),
    ]
    if "irsim" in result:
        c = result["irsim"]
        best = max(v["real_time_factor"] for v in c["variants"].values())
        rows.append(("(c) IR-SIM RTF (fastest variant)", f"{best:.0f}x", "", ""))
        rows.append(
            (
                "(a) / (c)",
                f"{c['ratio_vs_fastest_variant']:.1f}x",
                f">= {TARGET_RATIO:.0f}x",
                verdict(c["ratio_vs_fastest_variant"], TARGET_RATIO),
            )
        )
    print(table(rows, ("measure", "value", "target", "")))
    save_results("run", result)
    print(f"\nwrote {Path('benchmarks/results.json')}")
    return result


if __name__ == "__main__":
    main()
