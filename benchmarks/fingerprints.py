"""Run fingerprints: a hash of what every shipped mission does, to prove a refactor changed nothing.

Each shipped mission (``missions/*.yaml``) runs through the command line (``thymio-bt run``, the
contract, so the script outlives any internal API) on three robot models (course, enki, real) with
the noise off and with the sweep's noise on for three seeds. A fingerprint is the SHA-256 of the
run report without its wall-clock fields, and of every tick line of the run's JSON-lines log
(unrounded poses, readings, tree statuses). The log header (mission, maze, tree shape) is hashed
apart, so a changed header is told from a changed trajectory; the checkout's folder in it (a maze
file's absolute path) is replaced by ``<checkout>``, so that two clones of one commit agree.

Usage (from a checkout whose package the interpreter imports)::

    python benchmarks/fingerprints.py -o before.json          # record
    python benchmarks/fingerprints.py --check before.json     # compare; exit 1 on any difference
"""

from __future__ import annotations

import argparse
import concurrent.futures
import hashlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ("course", "enki", "real")
#: (seed, overrides): the mission's own noise, then the sweep's noise with three seeds
NOISE = ("noise.wheel=0.027", "noise.range_sd=0.001", "noise.odometry=0.01")
VARIANTS: tuple[tuple[int, tuple[str, ...]], ...] = ((0, ()), (1, NOISE), (2, NOISE), (3, NOISE))
WALL_CLOCK = ("wall_time", "real_time_factor")


def fingerprint(mission: Path, robot: str, seed: int, overrides: tuple[str, ...]) -> dict[str, str]:
    """Run ``mission`` once in a child process; the hashes of its report, log header and ticks."""
    with tempfile.TemporaryDirectory() as folder:
        report, log = Path(folder) / "r.json", Path(folder) / "l.jsonl"
        command = [sys.executable, "-m", "thymio_bt", "run", str(mission), "-q", "--robot", robot]
        command += ["--seed", str(seed), "--report", str(report), "--log", str(log)]
        for override in overrides:
            command += ["--set", override]
        done = subprocess.run(command, capture_output=True, text=True, cwd=folder)
        if done.returncode not in (0, 1):
            return {"error": done.stderr.strip()[-300:]}
        data = json.loads(report.read_text())
        for key in WALL_CLOCK:
            data.pop(key, None)
        header, *ticks = log.read_text().splitlines()
        header = header.replace(str(ROOT), "<checkout>")  # the same run from any clone hashes the same
        return {
            "report": hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest(),
            "header": hashlib.sha256(header.encode()).hexdigest(),
            "ticks": hashlib.sha256("\n".join(ticks).encode()).hexdigest(),
        }


def all_fingerprints(workers: int) -> dict[str, dict[str, str]]:
    """Every shipped mission x robot x variant, keyed ``mission/robot/seed``."""
    jobs = {
        f"{mission.stem}/{robot}/{seed}{'+noise' if overrides else ''}": (mission, robot, seed, overrides)
        for mission in sorted((ROOT / "missions").glob("*.yaml"))
        for robot in ROBOTS
        for seed, overrides in VARIANTS
    }
    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        futures = {key: pool.submit(fingerprint, *job) for key, job in jobs.items()}
        return {key: future.result() for key, future in futures.items()}


def _parts_differing(before: dict[str, str], now: dict[str, str]) -> list[str]:
    """Which hashes of one run differ (``report``, ``header``, ``ticks``; ``error`` if one failed)."""
    return [part for part in ("report", "header", "ticks", "error") if before.get(part) != now.get(part)]


def main() -> int:
    """Record fingerprints (``-o``) or compare them with a recorded file (``--check``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, help="write the fingerprints here (JSON)")
    parser.add_argument("--check", type=Path, help="compare with these recorded fingerprints")
    parser.add_argument("--workers", type=int, default=2, help="runs at once (default 2)")
    args = parser.parse_args()
    now = all_fingerprints(args.workers)
    errors = [key for key, value in now.items() if "error" in value]
    for key in errors:
        print(f"{key}: the run failed: {now[key]['error']}", file=sys.stderr)
    if args.output:
        args.output.write_text(json.dumps(now, indent=1, sort_keys=True) + "\n")
    if args.check:
        before = json.loads(args.check.read_text())
        differ = [f"{key}: {', '.join(_parts_differing(before.get(key, {}), value))}" for key, value in now.items()]
        differ = [line for line in differ if not line.endswith(": ")]
        print("\n".join(differ) or f"all {len(now)} fingerprints identical")
        return 1 if differ or errors else 0
    print(f"{len(now)} fingerprints written to {args.output}" if args.output else json.dumps(now, indent=1))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
