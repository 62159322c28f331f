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

# the interface's names, as its __all__ declares them (one list, not a copy to keep in step)
from thymio_bt.robot.interface import *  # noqa: F403
from thymio_bt.robot.interface import __all__ as __all__
