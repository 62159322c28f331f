"""A Groot2 log (.btlog) read back: its statuses per tick are the JSON-lines log's, ``view`` draws it
alone (no robot) or with the robot of a log of the same run (``--poses``); a cut or foreign file."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from test_viewer import CONTRACT, expected, record

from thymio_bt.btcpp.btlog import MAGIC, NO_POSES, RECORD
from thymio_bt.errors import UserError
from thymio_bt.logs import read_log

#: 30 subtrees, each using the next twice: 2**30 nodes if expanded blindly, 60 levels deep
NESTED = "".join(
    f'<BehaviorTree ID="T{i}"><Sequence _uid="1"><SubTree ID="T{i + 1}" _uid="2"/><SubTree ID="T{i + 1}" _uid="3"/>'
    "</Sequence></BehaviorTree>"
    for i in range(30)
)
LOOP = f'<root main_tree_to_execute="T0">{NESTED}<BehaviorTree ID="T30"><Stop _uid="1"/></BehaviorTree></root>'.encode()


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> tuple[Path, Path]:
    """maze_part1_2 run once, written as a .btlog and as JSON lines."""
    folder = tmp_path_factory.mktemp("btlog")
    record("maze_part1_2", folder / "run.jsonl")
    record("maze_part1_2", folder / "run.btlog")
    return folder / "run.btlog", folder / "run.jsonl"


def thymio_bt(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "thymio_bt", *map(str, args)], capture_output=True, text=True)


def view(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return thymio_bt("view", *args)


def test_the_btlog_statuses_are_the_jsonl_ones_at_every_tick(logs):
    btlog, jsonl = logs
    statuses, full = read_log(btlog), read_log(jsonl)
    tree = [node["path"] for node in statuses.header["tree"]]
    assert tree == [node["path"] for node in full.header["tree"]]  # every node of maze_part1_2 is in BT.CPP's tree
    at = {s["t"]: s for s in full.samples}
    assert len(statuses.samples) > 10
    for sample in statuses.samples:  # a sample per record time: every status then is the log's
        assert sample["nodes"] == at[sample["t"]]["nodes"], sample["t"]
        assert sample["tick"] == at[sample["t"]]["tick"] and sample["pose"] is None
    # between two record times nothing changed: the JSONL's ticks keep the last record's statuses
    times = [s["t"] for s in statuses.samples]
    for sample in full.samples[1:]:
        last = max(i for i, t in enumerate(times) if t <= sample["t"]) if sample["t"] >= times[0] else None
        if last is not None:
            assert sample["nodes"] == statuses.samples[last]["nodes"], sample["t"]


def test_replaying_a_btlog_says_how_the_run_ended_and_its_ticks_as_the_jsonl_does(logs):
    """Before: "UNKNOWN after 32.7 s simulated, 23 ticks": the root's last status was not read, and
    the records (one per time some status changed) were counted as ticks."""
    btlog, jsonl = logs
    said = {log.suffix: thymio_bt("replay", log).stdout.splitlines()[0] for log in (btlog, jsonl)}
    records = read_log(btlog).end["records"]
    assert said[".jsonl"].startswith("maze_part1_2: SUCCESS after ")
    assert said[".btlog"] == said[".jsonl"].replace("maze_part1_2", "run") + f" ({records} status records)"
    assert 10 < records < len(read_log(jsonl).samples)


def test_a_cut_btlog_is_read_up_to_its_last_whole_record(logs, tmp_path):
    btlog, _ = logs
    data = btlog.read_bytes()
    cut = tmp_path / "cut.btlog"
    cut.write_bytes(data[: len(data) - 2 * RECORD - 4])
    whole, part = read_log(btlog), read_log(cut)
    assert part.header["damaged_at"] == len(data) - 3 * RECORD and part.end["status"] == "INCOMPLETE"
    assert (
        part.samples[-1]["t"] <= whole.samples[-1]["t"] and part.samples[:-1] == whole.samples[: len(part.samples) - 1]
    )
    assert "damaged_at" not in whole.header
    done = view(cut, "-o", tmp_path / "cut.html")
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize(
    "content, message",
    [
        (b'{"kind": "header"}\n', "not a Groot2 log"),
        (b"", "not a Groot2 log"),
        (MAGIC + b"\x01\xff\xff\x00\x00<root/>", "damaged Groot2 log head"),
        (MAGIC + b"\x01\x07\x00\x00\x00<root/>" + bytes(8), "has no <BehaviorTree>"),
        (MAGIC + b"\x01" + len(LOOP).to_bytes(4, "little") + LOOP + bytes(8), "expands to more than 65535 nodes"),
    ],
)
def test_a_file_that_is_not_a_btlog_is_a_clear_error(tmp_path, content, message):
    junk = tmp_path / "junk.btlog"
    junk.write_bytes(content)
    with pytest.raises(UserError, match=message):
        read_log(junk)
    done = view(junk)
    assert done.returncode == 2 and message in done.stderr + done.stdout and "Traceback" not in done.stderr


def test_poses_goes_with_one_btlog_only(logs, tmp_path):
    btlog, jsonl = logs
    done = view(jsonl, "--poses", jsonl, "-o", tmp_path / "x.html")
    assert done.returncode == 2 and "--poses goes with one .btlog" in done.stdout + done.stderr


def test_the_btlog_page_with_poses_shows_what_the_jsonl_page_shows(browser, logs, tmp_path):  # noqa: F811
    btlog, jsonl = logs
    pages = {name: tmp_path / f"{name}.html" for name in ("jsonl", "merged", "alone")}
    for args, page in (
        ((jsonl,), pages["jsonl"]),
        ((btlog, "--poses", jsonl), pages["merged"]),
        ((btlog,), pages["alone"]),
    ):
        done = view(*args, "-o", page)
        assert done.returncode == 0, done.stderr
    samples = read_log(jsonl).samples
    at = {s["t"]: s for s in samples}
    tabs = {name: browser.open(page.as_uri() + "#t=0") for name, page in pages.items()}
    for fragment in ("t=3.2", "t=12.3", "t=20.05", f"tick={samples[-1]['tick']}"):
        seen = {}
        for name, tab in tabs.items():
            tab.evaluate(f"location.hash = {json.dumps('#' + fragment)}")
            tab.evaluate("new Promise(r => setTimeout(r, 0))")
            seen[name] = tab.evaluate(CONTRACT)
        assert seen["merged"] == seen["jsonl"], fragment
        # alone: the same tree and statuses, no robot
        assert seen["alone"]["pose"] == "" and seen["alone"]["nodes"] == seen["jsonl"]["nodes"], fragment
    assert seen["jsonl"] == expected(samples[-1]) and at[12.3]["pose"] is not None
    assert NO_POSES in tabs["alone"].evaluate("document.getElementById('announce').textContent")
    assert NO_POSES not in tabs["merged"].evaluate("document.getElementById('announce').textContent")
    for tab in tabs.values():
        assert tab.problems() == []
        tab.close()


def test_export_refuses_a_btlog_it_has_no_robot_to_write(logs, tmp_path):
    btlog, _ = logs
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "export", str(btlog), "-o", str(tmp_path / "x.mcap")],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 2 and "holds node statuses only, no robot" in done.stderr + done.stdout
    assert "Traceback" not in done.stderr and not (tmp_path / "x.mcap").exists()
