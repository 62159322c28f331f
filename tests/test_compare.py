"""``thymio-bt compare``: a run against itself (every difference 0, no divergence, exit 0), two seeds
(the divergence at the first differing tick, exit 1 past a tight tolerance), its JSON contract, the
plot, `--backends`, and bad input (one log, a bad tolerance, a damaged or cut log) without a traceback."""

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.logs import read_log
from thymio_bt.run.divergence import first_divergence

MISSION = str(Path(__file__).resolve().parent.parent / "missions" / "maze_part1_2.yaml")
NOISE = ["--set", "noise.wheel=0.027", "--set", "noise.range_sd=0.001", "--set", "noise.odometry=0.01"]


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("compare")
    for seed in (1, 2):
        result = invoke("run", MISSION, "-q", "--seed", seed, *NOISE, "--log", folder / f"seed{seed}.jsonl")
        assert result.exit_code == 0, result.output
    return folder / "seed1.jsonl", folder / "seed2.jsonl"


def test_a_run_against_itself_differs_by_nothing(logs, tmp_path):
    out = tmp_path / "same.json"
    result = invoke("compare", logs[0], logs[0], "--json", out)
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert set(data) == {"phases", "divergence"} and data["divergence"] is None
    assert len(data["phases"]) == 26
    for phase in data["phases"]:
        assert set(phase) == {"node", "occurrence", "a", "b", "diff"}
        assert phase["a"] == phase["b"]
        assert all(v == 0 for v in phase["diff"].values()), phase
    assert "no divergence" in result.output and "agree within the tolerances" in result.output


def test_two_seeds_diverge_at_their_first_differing_tick(logs, tmp_path):
    out = tmp_path / "seeds.json"
    result = invoke("compare", logs[0], logs[1], "--json", out)
    data = json.loads(out.read_text())
    expected = first_divergence(read_log(logs[0]), read_log(logs[1]))
    assert expected is not None
    assert data["divergence"] == json.loads(json.dumps(expected.to_json()))
    assert set(data["divergence"]) == {"time", "tick", "reason", "a", "b"}
    assert f"first divergence at {expected.time:g} s (tick {expected.tick})" in result.output
    part1 = data["phases"][0]
    assert (part1["node"], part1["occurrence"], part1["a"]["kind"]) == ("course/part 1", 1, "MoveUntilWall")
    assert part1["diff"]["front"] == pytest.approx(part1["b"]["front"] - part1["a"]["front"], abs=1e-6)
    turns = [p for p in data["phases"] if p["node"].endswith("TurnAngle")]
    assert [p["occurrence"] for p in turns] == [1, 2, 3, 4] and all("turned_deg" in p["a"] for p in turns)
    # the seeds end 0.6 s apart: past the default time tolerance (0.5 s), within 2 s; 1 mm holds the gaps apart
    assert result.exit_code == 1 and "the runs differ: 2 values past the tolerances" in result.output
    assert invoke("compare", logs[0], logs[1], "--tolerance", "time=2s").exit_code == 0
    tight = invoke("compare", logs[0], logs[1], "--tolerance", "gap=1mm,time=0.05s")
    assert tight.exit_code == 1 and "past the tolerances" in tight.output
    assert "  !" in tight.output


def test_the_plot_overlays_both_runs(logs, tmp_path):
    out = tmp_path / "compare.png"
    assert invoke("compare", logs[0], logs[1], "--plot", out, "--tolerance", "time=2s").exit_code == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_two_backends_run_from_the_same_seed_and_start(tmp_path):
    out = tmp_path / "backends.json"
    result = invoke("compare", MISSION, "--backends", "sim,sim", "--seed", "3", *NOISE, "--json", out)
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert data["divergence"] is None and all(p["a"] == p["b"] for p in data["phases"])


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["only.jsonl"], "compare takes two run logs"),
        (["a.jsonl", "b.jsonl", "c.jsonl"], "compare takes two run logs"),
        ([MISSION, "--backends", "sim"], "--backends takes two backends"),
        (["{0}", "{0}", "--tolerance", "speed=3"], "unknown tolerance 'speed'"),
        (["{0}", "{0}", "--tolerance", "gap=2deg"], "gap: '2deg' is not a length"),
        (["{0}", "missing.jsonl"], "log not found"),
        (["{0}", "{0}", "--plot", "out.svg"], "the plot is a PNG"),
    ],
)
def test_bad_input_is_one_message(logs, args, message):
    result = invoke("compare", *[a.format(logs[0]) for a in args])
    assert result.exit_code == 2, result.output
    assert message in result.output and "Traceback" not in result.output


def test_a_damaged_or_cut_log_is_compared_up_to_its_last_whole_tick(logs, tmp_path):
    lines = logs[0].read_text().splitlines()
    damaged = tmp_path / "damaged.jsonl"
    damaged.write_text("\n".join(lines[:101] + ['{"kind": "tick"}'] + lines[102:]) + "\n")
    result = invoke("compare", logs[0], damaged)
    assert result.exit_code == 1  # B stops at 10 s: its later phases are missing
    assert "damaged.jsonl:102: damaged line; kept the 100 ticks before it" in result.output
    assert "run B ended at" in result.output and "only in A" in result.output
    cut = tmp_path / "cut.jsonl"
    cut.write_text("\n".join(lines[:151]) + "\n" + lines[151][:20])
    result = invoke("compare", cut, logs[0])
    assert "the log is cut short; kept its 150 ticks" in result.output and "Traceback" not in result.output


def test_angles_are_compared_around_the_circle(logs):
    from thymio_bt.run.comparison import compare

    a, b = read_log(logs[0]), read_log(logs[0])
    west = next(s for s in a.samples if s["pose"] and abs(s["pose"]["yaw"]) > math.radians(179.5))
    index = a.samples.index(west)
    b.samples[index] = {**west, "pose": {**west["pose"], "yaw": -west["pose"]["yaw"]}}  # the other side of ±180
    turned = math.degrees(abs(math.remainder(2 * west["pose"]["yaw"], math.tau)))
    found = compare(a, b)
    assert found.divergence is None or found.divergence.time != west["t"]  # under 1 degree apart, not 359
    for phase in found.phases:
        if phase.a is not None and phase.diff is not None and phase.a["time"] == west["t"]:
            assert abs(float(phase.diff["yaw_deg"])) == pytest.approx(turned, abs=1e-3)


def test_a_log_with_junk_events_is_compared_without_a_traceback(logs, tmp_path):
    lines = logs[0].read_text().splitlines()
    end = json.loads(lines[-1])
    end["events"] = [
        {"kind": "behaviour_end", "path": "course/part 1", "t": "soon", "range": 0.05},
        {"kind": "behaviour_end", "path": "course/part 1", "t": 4.2, "range": "far", "pose": "north"},
        {"kind": "behaviour_end", "path": ["x"], "t": 5.0, "angle": 1.5, "proximity": [1, 2], "name": 3},
        {"kind": "collision", "t": 4.0, "x": "here"},
    ]
    junk = tmp_path / "junk.jsonl"
    junk.write_text("\n".join([*lines[:-1], json.dumps(end)]) + "\n")
    out = tmp_path / "junk.json"
    result = invoke("compare", logs[0], junk, "--json", out)
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    phases = json.loads(out.read_text())["phases"]
    junk_part1 = next(p for p in phases if p["node"] == "course/part 1")
    assert "front" not in junk_part1["b"] and junk_part1["b"]["time"] == 4.2
