"""The real-robot backends: a Thymio II behind :class:`ThymioRobot` (:mod:`.thymio`), reached through
the Thymio Device Manager (:class:`TdmDevice`, ``thymio-bt[thymio]``) or over its own Aseba protocol
(:mod:`.aseba`, ``thymio-bt[aseba]``).

tdmclient and thymiodirect are imported only when a device connects, so this package imports without
the optional extras.
"""

from thymio_bt.backends.real.thymio import PROX_INDEX, AsebaDevice, TdmDevice, ThymioRobot, import_tdmclient

__all__ = ["PROX_INDEX", "AsebaDevice", "TdmDevice", "ThymioRobot", "import_tdmclient"]
