"""Runs as rosbag2 bags with MCAP storage: the course's topics, with standard message types.

Foxglove, Lichtblick, PlotJuggler and ``ros2 bag play`` open them without thymio-bt. Messages are
serialised by the ``rosbags`` library (ROS 2 Humble's types, as the course's Gazebo uses), never by
hand. Topics, stamped with the simulated time:

- ``/clock`` (rosgraph_msgs/Clock), ``/cmd_vel`` (geometry_msgs/Twist)
- ``/odom`` (nav_msgs/Odometry, frame ``odom`` = the world, child ``base_footprint``, as the
  course's diff-drive plugin) and ``/tf`` (tf2_msgs/TFMessage, the same transform)
- ``/thymio_<prefix>_sensor`` (sensor_msgs/LaserScan, one ray, ``inf`` when nothing is in range)
  for the seven proximity sensors, frame ``<prefix>_link``
- ``/behavior_tree/status`` and ``/behavior_tree/events`` (std_msgs/String, JSON: the status of
  every node per tick, and the run's events) and ``/thymio_bt/header`` (the log header, once)

A path ending in ``.mcap`` is written as one MCAP file (the bag's only file); a path without a
suffix as a rosbag2 folder (``metadata.yaml`` and the MCAP file).
"""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

from thymio_bt.errors import Problem, UserError
from thymio_bt.logs.entries import LogEnd, LogHeader, TickRecord
from thymio_bt.logs.recording import Recording
from thymio_bt.robot.interface import SENSOR_NAMES

_INSTALL = "pip install 'thymio-bt[rosbag]'"
#: sensor name -> the course's topic prefix (docs/sources.md, "Robot geometry and sensors")
_PREFIX = {name: f"{name}_proximity" for name in SENSOR_NAMES}
_TYPES = {
    "/clock": "rosgraph_msgs/msg/Clock",
    "/cmd_vel": "geometry_msgs/msg/Twist",
    "/odom": "nav_msgs/msg/Odometry",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/behavior_tree/status": "std_msgs/msg/String",
    "/behavior_tree/events": "std_msgs/msg/String",
    "/thymio_bt/header": "std_msgs/msg/String",
    **{f"/thymio_{prefix}_sensor": "sensor_msgs/msg/LaserScan" for prefix in _PREFIX.values()},
}


def _rosbags() -> Any:
    try:
        import rosbags.rosbag2
        import rosbags.typesys
    except ImportError:
        raise UserError(f"rosbag2 logs need the rosbags library (hint: {_INSTALL})") from None
    return rosbags


def _ns(t: float) -> int:
    return round(t * 1e9)


class RosbagWriter:
    """Writes a run as a rosbag2 bag with MCAP storage (see the module docstring)."""

    def __init__(self, path: Path) -> None:
        rosbags = _rosbags()
        self.path = path
        self.folder = path.with_name(path.name + ".bag-tmp") if path.suffix else path
        if self.folder.exists():
            if path.suffix:
                shutil.rmtree(self.folder)
            else:
                raise UserError(
                    Problem(
                        f"{path} exists: rosbag2 writes a new folder", str(path), hint="remove it, or give another path"
                    )
                )
        self.store = rosbags.typesys.get_typestore(rosbags.typesys.Stores.ROS2_HUMBLE)
        self.types = self.store.types
        try:
            self.folder.parent.mkdir(parents=True, exist_ok=True)
            self.writer = rosbags.rosbag2.Writer(
                self.folder, version=9, storage_plugin=rosbags.rosbag2.StoragePlugin.MCAP
            )
            self.writer.open()
        except (OSError, rosbags.rosbag2.WriterError) as exc:
            raise UserError(f"cannot write the log {path}: {exc}") from None
        self.connections = {
            topic: self.writer.add_connection(topic, msgtype, typestore=self.store) for topic, msgtype in _TYPES.items()
        }
        self.frames: dict[str, str] = {}

    def _write(self, topic: str, t: float, msg: Any) -> None:
        self.writer.write(self.connections[topic], _ns(t), self.store.serialize_cdr(msg, _TYPES[topic]))

    def _stamp(self, t: float) -> Any:
        sec = math.floor(t)
        return self.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=round((t - sec) * 1e9))

    def _header(self, t: float, frame: str) -> Any:
        return self.types["std_msgs/msg/Header"](stamp=self._stamp(t), frame_id=frame)

    def _string(self, data: Any) -> Any:
        return self.types["std_msgs/msg/String"](data=json.dumps(data, separators=(",", ":")))

    def header(self, header: LogHeader) -> None:
        """Write the log header, as JSON on ``/thymio_bt/header`` at t = 0."""
        self._write("/thymio_bt/header", 0.0, self._string(header))

    def tick(self, record: TickRecord) -> None:
        """Write one tick's messages: clock, command, odometry and tf (with a robot), scans, tree status."""
        T, t = self.types, record["t"]
        v3, q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
        self._write("/clock", t, T["rosgraph_msgs/msg/Clock"](clock=self._stamp(t)))
        cmd = record["cmd"]
        self._write(
            "/cmd_vel",
            t,
            T["geometry_msgs/msg/Twist"](linear=v3(x=cmd[0], y=0.0, z=0.0), angular=v3(x=0.0, y=0.0, z=cmd[1])),
        )
        pose = record.get("pose")
        if pose is not None:
            half = pose["yaw"] / 2.0
            orientation = q(x=0.0, y=0.0, z=math.sin(half), w=math.cos(half))
            point = T["geometry_msgs/msg/Point"](x=pose["x"], y=pose["y"], z=0.0)
            vel = record["vel"]
            covariance = _zeros(36)
            odom = T["nav_msgs/msg/Odometry"](
                header=self._header(t, "odom"),
                child_frame_id="base_footprint",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](
                    pose=T["geometry_msgs/msg/Pose"](position=point, orientation=orientation), covariance=covariance
                ),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](
                    twist=T["geometry_msgs/msg/Twist"](
                        linear=v3(x=vel[0], y=0.0, z=0.0), angular=v3(x=0.0, y=0.0, z=vel[1])
                    ),
                    covariance=covariance,
                ),
            )
            self._write("/odom", t, odom)
            transform = T["geometry_msgs/msg/TransformStamped"](
                header=self._header(t, "odom"),
                child_frame_id="base_footprint",
                transform=T["geometry_msgs/msg/Transform"](
                    translation=v3(x=pose["x"], y=pose["y"], z=0.0), rotation=orientation
                ),
            )
            self._write("/tf", t, T["tf2_msgs/msg/TFMessage"](transforms=[transform]))
        for name, value in (record.get("prox") or {}).items():
            prefix = _PREFIX.get(name)
            if prefix is None:
                continue
            scan = T["sensor_msgs/msg/LaserScan"](
                header=self._header(t, f"{prefix}_link"),
                angle_min=-0.05,
                angle_max=0.05,
                angle_increment=0.1,
                time_increment=0.0,
                scan_time=0.1,
                range_min=0.0005,
                range_max=0.0975,
                ranges=_ranges(value),
                intensities=_zeros(0, "float32"),
            )
            self._write(f"/thymio_{prefix}_sensor", t, scan)
        if "nodes" in record:
            self._write(
                "/behavior_tree/status",
                t,
                self._string({"tick": record["tick"], "nodes": record["nodes"], "running": record["running"]}),
            )

    def end(self, end: LogEnd) -> None:
        """Write the run's events, then its outcome, on ``/behavior_tree/events``."""
        for event in end.get("events", []):
            self._write("/behavior_tree/events", float(event.get("t", 0.0)), self._string(event))
        last = end.get("sim_time", 0.0)
        self._write(
            "/behavior_tree/events",
            last,
            self._string({"t": last, "kind": "end", **{k: v for k, v in end.items() if k != "events"}}),
        )

    def close(self) -> None:
        """Finish the bag (a ``.mcap`` path: its one MCAP file moved there); idempotent."""
        if self.writer is None:
            return
        self.writer.close()
        self.writer = None
        if self.path.suffix:  # one MCAP file: the bag's only file, renamed
            (mcap,) = self.folder.glob("*.mcap")
            mcap.replace(self.path)
            shutil.rmtree(self.folder)


def _zeros(n: int, dtype: str = "float64") -> Any:
    import numpy as np

    return np.zeros(n, dtype=dtype)


def _ranges(value: float | None) -> Any:
    """A LaserScan's one range (inf: nothing in range, as Gazebo reports it)."""
    import numpy as np

    return np.array([math.inf if value is None else value], dtype=np.float32)


def read_rosbag(path: Path) -> Recording:
    """A run back from a bag this module wrote (a ``.mcap`` file or a rosbag2 folder)."""
    rosbags = _rosbags()
    from rosbags.highlevel import AnyReader

    from thymio_bt.inputs.validation import validate
    from thymio_bt.logs.bag_check import check_bag
    from thymio_bt.maze import Maze

    check_bag(path)
    bag = _BagContents()
    try:
        with AnyReader(
            [path], default_typestore=rosbags.typesys.get_typestore(rosbags.typesys.Stores.ROS2_HUMBLE)
        ) as reader:
            for connection, stamp, raw in reader.messages():
                # rosbags returns object: message classes are made at run time from the bag's typestore
                bag.add(connection.topic, stamp, reader.deserialize(raw, connection.msgtype))
    except UserError:
        raise
    except Exception as exc:  # rosbags' own errors: a damaged or foreign bag
        raise UserError(
            Problem(
                f"cannot read the bag: {type(exc).__name__}: {exc}",
                str(path),
                hint="bags are written by thymio-bt run --log FILE.mcap",
            )
        ) from None
    header = _checked_header(bag.header, path)
    header["exact"] = False  # float32 scans, a quaternion's yaw, 6 decimals: not the tree's numbers
    return Recording(
        maze=validate(Maze, header["maze"], str(path)),
        mission=header.get("mission", ""),
        samples=bag.samples(),
        events=bag.events,
        end=bag.end,
        header=header,
    )


def _checked_header(header: Any, path: Path) -> LogHeader:
    """The bag's log header; a user error when it has none, or not one with a maze."""
    if not header:
        raise UserError(Problem("not a thymio-bt bag: no /thymio_bt/header message", str(path)))
    if not isinstance(header, dict) or not isinstance(header.get("maze"), dict):
        raise UserError(
            Problem(
                "not a thymio-bt bag: its /thymio_bt/header message is not a log header with a maze",
                str(path),
                hint="bags are written by thymio-bt run --log FILE.mcap",
            )
        )
    return cast(LogHeader, header)  # the JSON of the bag's header message, its maze checked


#: the sensor each proximity topic is of
_SENSOR_OF = {f"/thymio_{prefix}_sensor": name for name, prefix in _PREFIX.items()}


class _BagContents:
    """A run as :func:`read_rosbag` gathers it from a bag's messages: each topic's into its place,
    the samples by time stamp."""

    def __init__(self) -> None:
        self.header: Any = {}
        self.ticks: dict[int, dict[str, Any]] = {}
        self.events: list[dict[str, Any]] = []
        self.end = LogEnd()

    def add(self, topic: str, stamp: int, msg: Any) -> None:
        """One message (``Any``: rosbags makes message classes at run time from the bag's typestore)."""
        sample = self.ticks.setdefault(stamp, {"t": round(stamp / 1e9, 6), "pose": None, "prox": {}})
        read = _READ.get(topic)
        if read is not None:
            read(self, topic, sample, msg)

    def samples(self) -> list[TickRecord]:
        """The samples of the ticks, in time order (a tick without a reading: its ``prox`` None)."""
        samples = [s for _, s in sorted(self.ticks.items()) if "tick" in s]
        for s in samples:
            s["prox"] = s["prox"] or None
        return cast(list[TickRecord], samples)  # each gathered from its messages as a tick record

    def _header(self, topic: str, sample: dict[str, Any], msg: Any) -> None:
        self.header = json.loads(msg.data)

    def _cmd_vel(self, topic: str, sample: dict[str, Any], msg: Any) -> None:
        sample["cmd"] = [msg.linear.x, msg.angular.z]

    def _odom(self, topic: str, sample: dict[str, Any], msg: Any) -> None:
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        sample["pose"] = {"x": p.x, "y": p.y, "yaw": round(2.0 * math.atan2(o.z, o.w), 6)}
        sample["vel"] = [msg.twist.twist.linear.x, msg.twist.twist.angular.z]

    def _range(self, topic: str, sample: dict[str, Any], msg: Any) -> None:
        value = float(msg.ranges[0])
        sample["prox"][_SENSOR_OF[topic]] = None if math.isinf(value) else round(value, 6)

    def _status(self, topic: str, sample: dict[str, Any], msg: Any) -> None:
        status = json.loads(msg.data)
        sample.update(tick=status["tick"], nodes=status["nodes"], running=status["running"])

    def _event(self, topic: str, sample: dict[str, Any], msg: Any) -> None:
        event = json.loads(msg.data)
        if event.get("kind") == "end":
            self.end = cast(LogEnd, {k: v for k, v in event.items() if k not in ("t", "kind")})
        else:
            self.events.append(event)


#: how each topic's message is read into the run
_READ: dict[str, Callable[[_BagContents, str, dict[str, Any], Any], None]] = {
    "/thymio_bt/header": _BagContents._header,
    "/cmd_vel": _BagContents._cmd_vel,
    "/odom": _BagContents._odom,
    **dict.fromkeys(_SENSOR_OF, _BagContents._range),
    "/behavior_tree/status": _BagContents._status,
    "/behavior_tree/events": _BagContents._event,
}
