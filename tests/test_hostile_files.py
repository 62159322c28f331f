"""Hostile files: a folder, a FIFO, a device, a huge file or a binary one, given as any kind of input
file to any command, is refused at once with one message naming it (exit 2, no traceback)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from thymio_bt.inputs.reading import LIMITS

ROOT = Path(__file__).resolve().parents[1]

#: every command that reads a file the user names, with where the file goes and its suffix
COMMANDS = {
    "run": (["run", "{}"], ".yaml", "mission"),
    "validate": (["validate", "{}"], ".yaml", "mission"),
    "tree": (["tree", "{}"], ".yaml", "mission"),
    "xml mission": (["run", "{}"], ".xml", "mission"),
    "--maze": (["run", str(ROOT / "missions/maze_6x6_left.yaml"), "--maze", "{}"], ".yaml", "maze"),
    "maze import": (["maze", "import", "{}"], ".world", "world"),
    "replay": (["replay", "{}"], ".jsonl", "log"),
    "export": (["export", "{}", "-o", "out.mcap"], ".jsonl", "log"),
    "sweep": (["sweep", "{}", "--runs", "2"], ".yaml", "mission"),
}


def cli(args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "thymio_bt", *args], cwd=cwd, capture_output=True, text=True, timeout=60
    )


def make(kind: str, tmp_path: Path, suffix: str, what: str) -> str:
    if kind == "device":
        return "/dev/zero"
    path = tmp_path / f"input{suffix}"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    elif kind == "huge":
        with open(path, "wb") as file:  # sparse: no disk used
            file.truncate(LIMITS[what] + 1)
    elif kind == "binary":
        path.write_bytes(b"name: x\n\xff\xfe\x00binary")
    return str(path)


KINDS = {
    "device": "not a regular file",
    "fifo": "not a regular file",
    "folder": "is a folder",
    "huge": "cap for",
    "binary": "not UTF-8 text",
}
# XML declares its own encoding, so the XML parser judges a binary .xml/.world (tested below)
CASES = [
    (command, kind)
    for command in COMMANDS
    for kind in KINDS
    if not (kind == "binary" and COMMANDS[command][1] in (".xml", ".world"))
]


@pytest.mark.parametrize("command, kind", CASES)
def test_a_hostile_input_file_is_refused_at_once(tmp_path, command, kind):
    args, suffix, what = COMMANDS[command]
    message = KINDS[kind]
    target = make(kind, tmp_path, suffix, what)
    done = cli([a.replace("{}", target) for a in args], tmp_path)
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and target in done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.splitlines()) <= 2


def test_an_include_that_is_a_fifo_is_refused(tmp_path):
    os.mkfifo(tmp_path / "legs.yaml")
    (tmp_path / "m.yaml").write_text("maze: two_parts_maze\nstart: part1\ninclude: [legs.yaml]\ntree: Stop\n")
    done = cli(["validate", "m.yaml"], tmp_path)
    assert done.returncode == 2 and "not a regular file" in done.stderr


def test_an_include_that_is_a_loop_of_symbolic_links_is_refused(tmp_path):
    (tmp_path / "a.yaml").symlink_to("b.yaml")
    (tmp_path / "b.yaml").symlink_to("a.yaml")
    (tmp_path / "m.yaml").write_text("maze: two_parts_maze\nstart: part1\ninclude: [a.yaml]\ntree: Stop\n")
    done = cli(["validate", "m.yaml"], tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "m.yaml:3:11: included file a.yaml is a loop of symbolic links" in done.stderr


@pytest.mark.parametrize("args, name", [(["validate", "m.xml"], "m.xml"), (["maze", "import", "w.world"], "w.world")])
def test_a_binary_xml_file_gets_a_message_not_a_traceback(tmp_path, args, name):
    (tmp_path / name).write_bytes(b"\xff\xfe\x00<root BTCPP_format='4'>")
    done = cli(args, tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr and name in done.stderr


FOREIGN = {
    "unknown encoding": '<?xml version="1.0" encoding="EBCDIC"?>\n<sdf><world name="w"/></sdf>\n',
    "entity": '<?xml version="1.0"?>\n<!DOCTYPE sdf [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n<sdf>&x;</sdf>\n',
    "external include": '<sdf><world name="w"><include><uri>http://127.0.0.1:9/m</uri></include></world></sdf>\n',
    "deep nesting": "<sdf><world name='w'>" + "<model name='m'>" * 5000 + "</model>" * 5000 + "</world></sdf>\n",
    "not XML": "walls:\n  - {from: [0, 0], to: [1, 0]}\n",
}


@pytest.mark.parametrize("case", list(FOREIGN))
@pytest.mark.parametrize("suffix, args", [(".world", ["maze", "import"]), (".xml", ["validate"])])
def test_a_foreign_or_tricky_xml_file_is_a_message_and_nothing_is_fetched(tmp_path, case, suffix, args):
    path = tmp_path / f"input{suffix}"
    path.write_text(
        FOREIGN[case].replace("<sdf", "<root").replace("</sdf>", "</root>") if suffix == ".xml" else FOREIGN[case]
    )
    done = cli([*args, str(path)], tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert str(path) in done.stderr and len(done.stderr.splitlines()) <= 2
    assert "root:" not in done.stderr + done.stdout  # /etc/passwd was not read
