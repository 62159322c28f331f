"""The robot: the interface behaviours drive (:mod:`.interface`), what a Thymio is as data
(:mod:`.model`, :mod:`.profile`, :mod:`.calibration`), how a profile is measured (:mod:`.calibrate`),
and where a robot may stand (:mod:`.placement`).

The interface's names are importable from here, as they were when it was one module::

    from thymio_bt.robot import Backend, Pose, Robot
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
