"""Damaged logs: `replay` and `export` of a truncated, binary, empty, wrong-typed or foreign log give
one message naming the line, and `--partial` replays what is readable before the damage."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def good_log(tmp_path_factory):
    path = tmp_path_factory.mktemp("log") / "ok.jsonl"
    assert CliRunner().invoke(main, ["run", f"{ROOT}/missions/square.yaml", "-q", "--log", str(path)]).exit_code == 0
    return path.read_text().splitlines()


def damaged(lines, tmp_path, how):
    path = tmp_path / "bad.jsonl"
    if how == "empty":
        path.write_text("")
    elif how == "foreign":
        path.write_text("time,x,y\n0,1,2\n")
    elif how == "binary":
        path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00")
    elif how == "json list":
        path.write_text("[1, 2, 3]\n")
    elif how == "header without maze":
        path.write_text(json.dumps({"kind": "header", "mission": "x"}) + "\n")
    elif how == "line 5 not JSON":
        path.write_text("\n".join(lines[:4] + ["{broken"] + lines[5:]) + "\n")
    elif how == "line 5 wrong type":
        tick = json.loads(lines[4])
        tick["pose"] = "north"
        path.write_text("\n".join(lines[:4] + [json.dumps(tick)] + lines[5:]) + "\n")
    elif how == "line 5 unknown kind":
        path.write_text("\n".join(lines[:4] + ['{"kind": "tock"}'] + lines[5:]) + "\n")
    return path


@pytest.mark.parametrize(
    "how, line, message",
    [
        ("empty", 0, "the log is empty"),
        ("foreign", 1, "not a thymio-bt log: invalid JSON"),
        ("binary", 0, "not UTF-8 text"),
        ("json list", 1, "the first line must be its header"),
        ("header without maze", 1, "header line: missing key 'maze'"),
        ("line 5 not JSON", 5, "damaged log line: invalid JSON"),
        ("line 5 wrong type", 5, "tick line: pose"),
        ("line 5 unknown kind", 5, "unknown line kind 'tock'"),
    ],
)
@pytest.mark.parametrize("command", [["replay"], ["export", "-o", "{tmp}/out.mcap"]])
def test_a_damaged_log_is_one_message_naming_the_line(good_log, tmp_path, how, line, message, command):
    path = damaged(good_log, tmp_path, how)
    args = [a.replace("{tmp}", str(tmp_path)) for a in command]
    result = CliRunner().invoke(main, [args[0], str(path), *args[1:]])
    assert result.exit_code == 2 and message in result.output, result.output
    assert (f"{path}:{line}:" in result.output) if line else (f"{path}:" in result.output)
    assert "Traceback" not in result.output and not (tmp_path / "out.mcap").exists()


def test_partial_replays_what_comes_before_the_damage(good_log, tmp_path):
    path = damaged(good_log, tmp_path, "line 5 wrong type")
    result = CliRunner().invoke(main, ["replay", "--partial", str(path)])
    assert result.exit_code == 0
    assert f"{path}:5: damaged line; kept the 3 ticks before it" in result.output
    assert "INCOMPLETE after 0.2 s simulated, 3 ticks" in result.output


def test_a_log_cut_mid_line_reads_without_being_asked(good_log, tmp_path):
    path = tmp_path / "cut.jsonl"
    path.write_text("\n".join(good_log[:10]) + "\n" + good_log[10][:20])
    result = CliRunner().invoke(main, ["replay", str(path)])
    assert result.exit_code == 0 and "INCOMPLETE" in result.output and "9 ticks" in result.output


def test_importing_the_logs_package_stays_light():
    """Every command that may write a log imports ``thymio_bt.logs``: a format's writer and reader, the
    recorder and the libraries they need are imported only when a log of that format is used."""
    heavy = ("py_trees", "pydantic", "pymunk", "numpy", "rosbags", "thymio_bt.logs.recording", "thymio_bt.logs.jsonl")
    code = f"import sys, thymio_bt.logs; print(','.join(m for m in {heavy!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


def _edit(lines, tmp_path, index, change):
    """The log with line ``index`` (0-based) parsed, changed by ``change`` and written back."""
    record = json.loads(lines[index])
    change(record)
    path = tmp_path / "bad.jsonl"
    path.write_text("\n".join([*lines[:index], json.dumps(record), *lines[index + 1 :]]) + "\n")
    return path


#: damage that replay used to read and export then tripped over (a traceback, half a file left)
EXPORT_DAMAGE = {
    "tree not a list": (0, lambda r: r.update(tree="nope"), "header line: tree"),
    "uid above 65535": (0, lambda r: r["tree"][0].update(uid=70000), "header line: tree.0.uid"),
    "parent unknown": (0, lambda r: r["tree"][1].update(parent=99), "parent 99 is not listed before it"),
    "unknown status letter": (4, lambda r: r["nodes"].update({next(iter(r["nodes"])): "Z"}), "tick line: nodes"),
    "tick without its number": (4, lambda r: r.pop("tick"), "tick line: missing key 'tick'"),
    "t = 1e300": (4, lambda r: r.update(t=1e300), "tick line: t"),
    "t negative": (4, lambda r: r.update(t=-5.0), "tick line: t"),
    "t going back": (4, lambda r: r.update(t=0.05), "is before the previous tick's"),
    "sim_time not a number": (-1, lambda r: r.update(sim_time="abc"), "end line: sim_time"),
}


@pytest.mark.parametrize("how", sorted(EXPORT_DAMAGE))
@pytest.mark.parametrize(
    "command", [["replay"], ["export", "-o", "{tmp}/out.mcap"], ["export", "--btlog", "{tmp}/out.btlog"]]
)
def test_damage_an_export_would_trip_on_is_found_when_reading(good_log, tmp_path, how, command):
    index, change, message = EXPORT_DAMAGE[how]
    path = _edit(good_log, tmp_path, index % len(good_log), change)
    args = [a.replace("{tmp}", str(tmp_path)) for a in command]
    result = CliRunner().invoke(main, [args[0], str(path), *args[1:]])
    assert result.exit_code == 2 and message in result.output, result.output
    line = index % len(good_log) + 1
    assert f"{path}:{line}:" in result.output and "Traceback" not in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.jsonl"]  # no partial .mcap, .btlog or bag-tmp


def _bag_with_header(path, header):
    from thymio_bt.logs.rosbag import RosbagWriter

    writer = RosbagWriter(path)
    writer.header(header)
    writer.close()
    return path


@pytest.mark.parametrize("header", [[1, 2, 3], {"mission": "no maze here"}, {"maze": "not a mapping"}])
def test_a_bag_whose_header_is_not_a_log_header_is_one_message(tmp_path, header):
    path = _bag_with_header(tmp_path / "odd.mcap", header)
    result = CliRunner().invoke(main, ["replay", str(path)])
    assert result.exit_code == 2, result.output
    assert "not a thymio-bt bag: its /thymio_bt/header message is not a log header" in result.output
    assert "Traceback" not in result.output


def _replay_in_a_child(path):
    """Replay ``path`` in a child process; its exit code, output and peak memory (MiB)."""
    code = (
        "import resource, subprocess, sys\n"
        f"done = subprocess.run([sys.executable, '-m', 'thymio_bt.cli', 'replay', {str(path)!r}],"
        " capture_output=True, text=True, timeout=60)\n"
        "peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024\n"
        "print(done.returncode, round(peak)); print(done.stdout + done.stderr)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=90).stdout
    head, _, text = out.partition("\n")
    rc, peak = map(int, head.split())
    return rc, text, peak


def _zip_bomb(log: Path, out: Path, declared: int | None) -> Path:
    """``log`` (an MCAP file thymio-bt wrote) with its first chunk replaced by 1.5 GiB of zeros
    packed with zstd (48 kB), declaring ``declared`` bytes (None: what the original chunk declared);
    no summary section, so a reader must walk the data."""
    import struct

    import zstandard

    packer = zstandard.ZstdCompressor(level=1).compressobj()
    zeros = bytes(1 << 20)
    packed = b"".join(packer.compress(zeros) for _ in range(1536)) + packer.flush()
    data, offset = log.read_bytes(), 8
    body_out, first = bytearray(data[:8]), True
    while offset + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, offset)
        body = data[offset + 9 : offset + 9 + length]
        offset += 9 + length
        if opcode == 0x06 and first:  # a chunk
            first = False
            start, end, unpacked, _ = struct.unpack_from("<QQQI", body)
            size = unpacked if declared is None else declared
            body = struct.pack("<QQQII", start, end, size, 0, 4) + b"zstd" + struct.pack("<Q", len(packed)) + packed
        elif opcode == 0x02:  # the footer: no summary, then the closing magic
            body_out += struct.pack("<BQ", opcode, 20) + bytes(20) + data[:8]
            break
        elif opcode not in (0x01, 0x0F):  # keep the header and the data end only
            continue
        body_out += struct.pack("<BQ", opcode, len(body)) + body
    out.write_bytes(bytes(body_out))
    return out


@pytest.mark.parametrize(
    "declared, message",
    [
        (1536 << 20, "a chunk of the bag unpacks to 1536 MiB, past the 64 MiB"),
        (None, "a zstd chunk unpacks to more than the"),  # it lies: rosbags unpacked it whole (3.1 GB)
    ],
)
def test_an_mcap_zip_bomb_is_refused_before_it_is_unpacked(tmp_path, declared, message):
    log = tmp_path / "run.mcap"
    assert CliRunner().invoke(main, ["run", f"{ROOT}/missions/square.yaml", "-q", "--log", str(log)]).exit_code == 0
    bomb = _zip_bomb(log, tmp_path / "bomb.mcap", declared)
    assert bomb.stat().st_size < 100_000
    rc, text, peak = _replay_in_a_child(bomb)
    assert rc == 2 and message in text and "Traceback" not in text, text
    assert peak < 300, f"{peak} MiB used before refusing"


def test_a_rosbag2_folder_whose_mcap_is_a_fifo_is_refused_at_once(tmp_path):
    import os

    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {version: 9, storage_identifier: mcap}\n")
    os.mkfifo(bag / "bag_0.mcap")
    rc, text, _ = _replay_in_a_child(bag)  # a hang would hit the 60 s timeout, an error
    assert rc == 2 and "bag_0.mcap in the bag is not a regular file" in text and "Traceback" not in text, text


@pytest.mark.parametrize("suffix", [".mcap", ".btlog", ".jsonl", ""])  # "": a rosbag2 folder
def test_an_export_that_fails_midway_leaves_nothing_behind(good_log, tmp_path, monkeypatch, suffix):
    """Whole or not at all: the writer writes a staged file (outputs.Output.staged), renamed at the end."""
    import thymio_bt.logs as logs

    log = tmp_path / "in" / "ok.jsonl"
    log.parent.mkdir()
    log.write_text("\n".join(good_log) + "\n")
    real_open = logs.open_writer

    def failing_writer(path):
        writer = real_open(path)
        ticks = {"n": 0}
        tick = writer.tick

        def tick_then_fail(record):
            ticks["n"] += 1
            if ticks["n"] == 5:
                raise OSError(28, "No space left on device")
            tick(record)

        writer.tick = tick_then_fail
        return writer

    monkeypatch.setattr(logs, "open_writer", failing_writer)
    out = tmp_path / "out"
    out.mkdir()
    result = CliRunner().invoke(main, ["export", str(log), "-o", str(out / f"run{suffix}")])
    assert result.exit_code == 2 and "No space left on device" in result.output
    assert sorted(p.name for p in out.iterdir()) == []  # no partial file, no staged file or folder
