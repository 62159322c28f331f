"""The robot: the interface behaviours drive (:mod:`.interface`), what a Thymio is as data
(:mod:`.model`, :mod:`.profile`; its sensors' tables are :mod:`thymio_bt.sensor_tables`), how a
profile is measured (:mod:`.calibrate`), where a robot may stand (:mod:`.placement`), how its front
sensors see a corridor (:mod:`.corridor`) and its heading controller (:mod:`.pid`).

The interface's names are importable from here, as they were when it was one module; a robot
that does not say what it is, nor how late it is, is the course's robot, on time:

Example::

    >>> from thymio_bt.robot import Backend, Pose, Robot
    >>> Robot.model.name, Backend.latency
    ('course', 0.0)
"""

from thymio_bt.robot.interface import (
    ROBOT_ENTITY,
    SENSOR_NAMES,
    Backend,
    Collision,
    Entities,
    Pose,
    Request,
    RequestState,
    Robot,
    RobotLost,
    Scan,
    Twist,
    new_pose,
    wrap_angle,
)

__all__ = [
    "ROBOT_ENTITY",
    "SENSOR_NAMES",
    "Backend",
    "Collision",
    "Entities",
    "Pose",
    "Request",
    "RequestState",
    "Robot",
    "RobotLost",
    "Scan",
    "Twist",
    "new_pose",
    "wrap_angle",
]
