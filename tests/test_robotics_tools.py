"""Runs and trees in the robotics tools' formats, each checked with the format's own reader:
rosbag2/MCAP (rosbags and mcap_ros2), BT.CPP XML (BehaviorTree.CPP via behaviortreepy), and the
Groot2 log (a parser written here from FileLogger2's layout)."""

import json
import math
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from _ports import free_port_pair
from _require import module
from _waiting import wait_until

ROOT = Path(__file__).resolve().parents[1]

MISSIONS = sorted((ROOT / "missions").glob("*.yaml"))


def thymio_bt(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "thymio_bt.cli", *map(str, args)], capture_output=True, text=True, cwd=cwd
    )


@pytest.fixture(scope="module")
def part1_2(tmp_path_factory):
    """One run of maze_part1_2 with a JSON-lines log and a bag, and its report."""
    module("rosbags")
    folder = tmp_path_factory.mktemp("run")
    done = thymio_bt(
        "run",
        f"{ROOT}/missions/maze_part1_2.yaml",
        "--log",
        folder / "run.mcap",
        "--report",
        folder / "report.json",
        "-q",
    )
    assert done.returncode == 0, done.stderr
    done = thymio_bt("run", f"{ROOT}/missions/maze_part1_2.yaml", "--log", folder / "run.jsonl", "-q")
    assert done.returncode == 0, done.stderr
    return folder, json.loads((folder / "report.json").read_text())


def test_the_bag_odometry_is_the_report_trajectory(part1_2):
    make_reader, decoders = module("mcap.reader").make_reader, module("mcap_ros2.decoder")
    folder, report = part1_2
    odom, topics = [], {}
    with (folder / "run.mcap").open("rb") as bag:
        reader = make_reader(bag, decoder_factories=[decoders.DecoderFactory()])
        for schema, channel, message, ros_msg in reader.iter_decoded_messages():
            topics[channel.topic] = schema.name
            if channel.topic == "/odom":
                p, q = ros_msg.pose.pose.position, ros_msg.pose.pose.orientation
                odom.append((message.log_time / 1e9, p.x, p.y, 2 * math.atan2(q.z, q.w)))
    trajectory = {round(s[0], 6): s[1:] for s in report["trajectory"]}
    assert len(odom) == len(trajectory) == 328  # 329 ticks, one without a robot (deleted)
    for t, x, y, yaw in odom:
        rx, ry, ryaw = trajectory[round(t, 6)]
        assert (x, y) == pytest.approx((rx, ry), abs=1e-6)
        assert math.remainder(yaw - ryaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-5)
    assert topics["/cmd_vel"] == "geometry_msgs/msg/Twist" and topics["/odom"] == "nav_msgs/msg/Odometry"
    assert topics["/tf"] == "tf2_msgs/msg/TFMessage" and topics["/clock"] == "rosgraph_msgs/msg/Clock"
    assert topics["/thymio_front_center_proximity_sensor"] == "sensor_msgs/msg/LaserScan"


def test_the_bag_scans_are_the_logged_readings_with_inf_for_nothing(part1_2):
    highlevel = module("rosbags.highlevel")
    folder, report = part1_2
    log = [json.loads(line) for line in (folder / "run.jsonl").read_text().splitlines()]
    logged = [t["prox"]["rear_left"] for t in log[1:-1] if t["prox"] is not None]
    with highlevel.AnyReader([folder / "run.mcap"]) as reader:
        rear = [c for c in reader.connections if c.topic == "/thymio_rear_left_proximity_sensor"]
        scans = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=rear)]
    ranges = [float(m.ranges[0]) for m in scans]
    assert [math.isinf(r) for r in ranges] == [v is None for v in logged] and any(map(math.isinf, ranges))
    assert [r for r in ranges if not math.isinf(r)] == pytest.approx([v for v in logged if v is not None], abs=1e-6)
    assert scans[-1].header.frame_id == "rear_left_proximity_link" and scans[-1].range_max == pytest.approx(0.0975)


def test_replay_and_export_read_a_bag_back(part1_2, tmp_path):
    folder, report = part1_2
    done = thymio_bt("replay", folder / "run.mcap")
    assert done.returncode == 0 and "SUCCESS" in done.stdout and "329 ticks" in done.stdout
    done = thymio_bt("export", folder / "run.jsonl", "-o", tmp_path / "converted")  # a rosbag2 folder
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "converted" / "metadata.yaml").is_file()
    again = thymio_bt("replay", tmp_path / "converted")
    assert again.stdout.splitlines()[0] == done.stdout.splitlines()[0] if done.stdout else "SUCCESS" in again.stdout


def parse_btlog(data: bytes):
    """FileLogger2's layout, read from its description (BehaviorTree.CPP bt_file_logger_v2.cpp)."""
    assert data[:18] == b"BTCPP4-FileLogger2" and data[18] == 1
    (size,) = struct.unpack_from("<i", data, 19)
    xml = data[23 : 23 + size].decode()
    (start,) = struct.unpack_from("<q", data, 23 + size)
    body = data[31 + size :]
    assert len(body) % 9 == 0
    records = [
        (int.from_bytes(body[i : i + 6], "little"), *struct.unpack_from("<HB", body, i + 6))
        for i in range(0, len(body), 9)
    ]
    return xml, start, records


def test_the_groot2_log_holds_one_record_per_status_change(part1_2, tmp_path):
    from thymio_bt.btcpp.export import btcpp_tree
    from thymio_bt.mission import default_registry

    folder, _ = part1_2
    done = thymio_bt("export", folder / "run.jsonl", "--btlog", tmp_path / "run.btlog")
    assert done.returncode == 0, done.stderr
    xml, start, records = parse_btlog((tmp_path / "run.btlog").read_bytes())
    log = [json.loads(line) for line in (folder / "run.jsonl").read_text().splitlines()]
    # each node by its element's _uid: BT.CPP's numbering (test_btcpp_export checks it against BT.CPP's)
    numbered = btcpp_tree(log[0]["tree"], default_registry())
    assert numbered.xml == xml
    tree = {n["path"]: numbered.uids[n["uid"]] for n in log[0]["tree"]}
    uids_in_xml = sorted(int(u) for u in re.findall(r'_uid="(\d+)"', xml))
    assert uids_in_xml == list(range(1, 23)) and start == 0  # 16 nodes of ours, 6 of a do-while loop
    expected, last = [], {path: "-" for path in tree}
    code = {"-": 0, "R": 1, "S": 2, "F": 3}
    for tick in log[1:-1]:
        for path, status in tick["nodes"].items():
            if last[path] != status:
                last[path] = status
                expected.append((round(tick["t"] * 1e6), tree[path], code[status]))
    assert records == expected and len(records) > 100
    assert (0, 1, 1) in records and records[-1][2] == 2  # the root (uid 1) runs from t = 0; the run succeeds


@pytest.mark.parametrize("mission", MISSIONS, ids=[m.stem for m in MISSIONS])
def test_every_mission_exports_to_xml_that_behaviortree_cpp_accepts(mission, tmp_path):
    bt = module("behaviortreepy")
    out = tmp_path / "tree.xml"
    done = thymio_bt("tree", mission, "--btcpp", out)
    assert done.returncode == 0, done.stderr
    xml = out.read_text()
    factory = bt.BehaviorTreeFactory()
    model = re.search(r"<TreeNodesModel>(.*)</TreeNodesModel>", xml, re.S).group(1)
    register = {
        "Action": factory.register_simple_action,
        "Condition": factory.register_simple_condition,
        "Decorator": factory.register_simple_decorator,
    }
    for tag, ident in re.findall(r'<(Action|Condition|Decorator|Control) ID="([^"]+)"', model):
        if tag in register:
            register[tag](ident, lambda *args: bt.NodeStatus.SUCCESS)
    # behaviortreepy cannot register a Python control node: check RepeatUntil's place as a sequence
    checked = xml.replace("<RepeatUntil ", "<SequenceWithMemory ").replace("</RepeatUntil>", "</SequenceWithMemory>")
    factory.register_behavior_tree_from_text(checked)  # BT.CPP's own verification; raises if invalid
    assert "MainTree" in factory.registered_behavior_trees()


@pytest.mark.parametrize("mission", MISSIONS, ids=[m.stem for m in MISSIONS])
def test_a_mission_exported_to_xml_runs_to_the_identical_report(mission, tmp_path):
    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    xml = tmp_path / f"{mission.stem}.xml"
    xml.write_text(mission_xml(load_mission(mission), xml))
    reports = [Run(load_mission(path), seed=7).run().report() for path in (mission, xml)]
    for report in reports:
        report.pop("wall_time"), report.pop("real_time_factor")
    assert reports[0] == reports[1]
    assert thymio_bt("validate", xml).returncode == 0


@pytest.mark.parametrize(
    "change, message, hint",
    [
        (("<MoveUntilWall ", "<MoveUntilWal "), "unknown node type 'MoveUntilWal'", "did you mean 'MoveUntilWall'?"),
        (('distance="0.05"', 'distance="5 apples"'), "unknown unit 'apples'", ""),
        (
            ('<SubTree ID="to_dead_end"', '<SubTree ID="to_dead_end" turn="left"'),
            "which <SubTree ID=\"to_dead_end\"> sets to the literal 'left'",
            "a literal port is read as its text",
        ),
        (("</root>", ""), "not a valid XML file", ""),
    ],
)
def test_xml_mission_errors_have_file_line_and_column(tmp_path, change, message, hint):
    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.mission import load_mission

    text = mission_xml(load_mission(f"{ROOT}/missions/maze_bonus.yaml"), tmp_path / "m.xml")
    old, new = change
    assert old in text
    broken = text.replace(old, new, 1)
    path = tmp_path / "m.xml"
    path.write_text(broken)
    done = thymio_bt("run", path)
    line = next(i for i, text in enumerate(broken.splitlines(), 1) if new and new.strip() in text) if new else None
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert message in done.stderr and hint in done.stderr, done.stderr
    if line:
        assert f"{path}:{line}:" in done.stderr


def test_an_xml_file_with_entities_is_refused(tmp_path):
    path = tmp_path / "bomb.xml"
    path.write_text(
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaa"><!ENTITY b "&a;&a;&a;">]>'
        '<root BTCPP_format="4"><BehaviorTree ID="T"><Stop name="&b;"/></BehaviorTree></root>'
    )
    done = thymio_bt("validate", path)
    assert (
        done.returncode == 2
        and "DOCTYPE and ENTITY declarations are not allowed in a mission" in done.stderr
        and f"{path}:1:" in done.stderr
    )


def _groot2_request(zmq, port, kind, payload=None, request_id=7):
    """One Groot2 protocol-2 request, written from BT.CPP's groot2_protocol.h, and its reply."""
    context = zmq.Context()
    socket = context.socket(zmq.REQ)
    socket.setsockopt(zmq.RCVTIMEO, 500)
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(f"tcp://127.0.0.1:{port}")
    try:
        socket.send_multipart([struct.pack("<BBI", 2, ord(kind), request_id)] + ([payload] if payload else []))
        return socket.recv_multipart()
    finally:
        context.destroy(linger=0)


def test_a_running_mission_is_served_to_groot2_clients(tmp_path):
    zmq = module("zmq")
    msgpack = module("msgpack")
    btview = _require_program_in_venv("btview")
    mission = (ROOT / "missions/maze_part1_2.yaml").resolve()
    xml = tmp_path / "tree.xml"
    thymio_bt("tree", mission, "--btcpp", xml)
    run, port, (head, tree) = _serving_groot2(zmq, mission, tmp_path)
    try:
        assert head[:6] == struct.pack("<BBI", 2, ord("T"), 7) and len(head) == 22
        assert tree.decode() == xml.read_text()  # the same XML as `tree --btcpp`, uids and all
        uids = [int(u) for u in re.findall(r'_uid="(\d+)"', tree.decode())]
        head, statuses = _groot2_request(zmq, port, "S")
        records = [struct.unpack_from("<HB", statuses, i) for i in range(0, len(statuses), 3)]
        assert sorted(uid for uid, _ in records) == sorted(uids) and records[0][1] == 1  # the root is RUNNING
        assert all(status in (0, 1, 2, 3, 11, 12, 13) for _, status in records)
        head, board = _groot2_request(zmq, port, "B", b"MainTree")
        assert set(msgpack.unpackb(board)) == {"MainTree"}
        assert _groot2_request(zmq, port, "Z") == [b"error"]
        shown = subprocess.run(
            [btview, "snapshot", "-p", str(port), "--ascii", "--no-color"],
            capture_output=True,
            text=True,
            timeout=30,
            env={**os.environ, "COLUMNS": "200", "LINES": "80"},  # the whole tree: it is cut to the screen
        )
        # 17 nodes of ours and the 6 BT.CPP built-ins that write repeat/until (docs/btcpp.md)
        assert "part 1 [MoveUntilWall]" in shown.stdout and "23 nodes" in shown.stdout, shown.stderr
        assert "part 2 [SubTree]" in shown.stdout  # the subtree as Groot2 shows one
    finally:
        run.terminate()
        run.wait(timeout=10)


def _serving_groot2(zmq, mission: Path, folder: Path) -> tuple[subprocess.Popen, int, list[bytes]]:
    """A run of ``mission`` serving Groot2 on a free pair of ports, the port, and its reply to ``T``
    (the server starts with the first tick). A pair another program took between its choice and the
    run's bind ends the run with "cannot serve Groot2": another pair is tried."""
    for _ in range(5):
        port = free_port_pair()
        command = [sys.executable, "-m", "thymio_bt.cli", "run", str(mission), "--realtime", "2", "-q"]
        run = subprocess.Popen([*command, "--groot2", str(port)], cwd=folder, stderr=subprocess.PIPE, text=True)
        try:
            reply = _first_reply(zmq, run, port)
        except BaseException:
            run.kill()
            raise
        if reply:
            return run, port, reply
        said = run.stderr.read() if run.stderr else ""
        assert "cannot serve Groot2" in said, said
    raise AssertionError("five pairs of free ports were taken before the run could bind them")


def _first_reply(zmq, run: subprocess.Popen, port: int) -> list[bytes]:
    """The reply to ``T`` once the run serves, or [] when the run ended first."""
    reply: list[bytes] = []

    def served() -> bool:
        reply[:] = _answers(zmq, port)  # waits up to 0.5 s for it
        return bool(reply) or run.poll() is not None

    wait_until(served, "a Groot2 reply", timeout=120, every=0)
    return reply


def _answers(zmq, port: int) -> list[bytes]:
    """The reply to a ``T`` request, or [] when none came within the request's timeout (0.5 s)."""
    try:
        return _groot2_request(zmq, port, "T")
    except zmq.Again:
        return []


def _require_program_in_venv(name):
    """A console script installed beside this Python (btview, Groot2's terminal client)."""
    path = Path(sys.executable).parent / name
    if not path.exists():
        from _require import missing

        missing(f"program {name}")
    return str(path)


def test_subtrees_are_their_own_behaviortrees_and_read_back(tmp_path):
    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.errors import UserError
    from thymio_bt.mission import load_mission

    xml = mission_xml(load_mission(f"{ROOT}/missions/course_full.yaml"))
    assert re.findall(r'<BehaviorTree ID="([^"]+)"', xml) == [
        "MainTree",
        "respawn",
        "to_dead_end",
        "respawn_2",
        "to_dead_end_2",
    ]
    assert '<SubTree ID="to_dead_end" name="part 2"' in xml
    uids = sorted(int(u) for u in re.findall(r'_uid="(\d+)"', xml))
    assert uids == list(range(1, 49))  # BT.CPP's pre-order: SubTree nodes and 2 do-while loops (6 each) included
    bad = tmp_path / "bad.xml"
    for body, message in (
        ('<SubTree ID="nowhere"/>', 'names no <BehaviorTree ID="nowhere">'),
        ('<SubTree ID="loop"/>', "subtree 'loop' uses itself"),
        ('<SubTree ID="loop" _autoremap="maybe"/>', '_autoremap="maybe" is not true or false'),
    ):
        bad.write_text(
            f'<root BTCPP_format="4" main_tree_to_execute="MainTree">\n'
            f'<BehaviorTree ID="MainTree">{body}</BehaviorTree>\n'
            f'<BehaviorTree ID="loop"><SubTree ID="loop"/></BehaviorTree>\n</root>\n'
        )
        with pytest.raises(UserError, match=re.escape(message)):
            load_mission(bad)


def test_the_page_says_what_the_export_does_with_subtrees(tmp_path):
    """docs/robotics_tools.md once said subtrees were "expanded in place": the export keeps them."""
    page = " ".join((ROOT / "docs/robotics_tools.md").read_text().split())
    assert "expanded in place" not in page and "Subtrees stay subtrees in the export" in page
    done = thymio_bt("tree", f"{ROOT}/missions/maze_part1_2.yaml", "--btcpp", tmp_path / "t.xml")
    assert done.returncode == 0, done.stderr
    xml = (tmp_path / "t.xml").read_text()
    assert '<SubTree ID="to_dead_end"' in xml and '<BehaviorTree ID="to_dead_end">' in xml
