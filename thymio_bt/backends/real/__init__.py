"""The real-robot backends: a Thymio II behind :class:`ThymioRobot` (:mod:`.thymio`), reached through
the Thymio Device Manager (:class:`TdmDevice`, ``thymio-bt[thymio]``) or over its own Aseba protocol
(:mod:`.aseba`, ``thymio-bt[aseba]``); their settings in :mod:`.options`.

tdmclient and thymiodirect are imported only when a device connects, so this package imports without
the optional extras; the robot's classes load from :mod:`.thymio` on first use, so that reading the
settings (``thymio-bt backends``) loads no robot code.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from thymio_bt.backends.real.thymio import PROX_INDEX, AsebaDevice, TdmDevice, ThymioRobot, import_tdmclient

__all__ = ["PROX_INDEX", "AsebaDevice", "TdmDevice", "ThymioRobot", "import_tdmclient"]


def __getattr__(name: str) -> Any:
    """The robot's classes, from :mod:`.thymio` on first use (PEP 562)."""
    if name in __all__:
        from thymio_bt.backends.real import thymio

        return getattr(thymio, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
