"""The real-robot backend: a Thymio II through the Thymio Device Manager (``thymio-bt[thymio]``).

tdmclient is imported only when :meth:`TdmNode.connect` (or :meth:`ThymioRobot.connect`) runs, so
this package imports without the optional extra.
"""

from thymio_bt.backends.real.thymio import (
    PLAYGROUND,
    PROX_INDEX,
    Node,
    RealConfig,
    TdmNode,
    ThymioRobot,
    import_tdmclient,
)

__all__ = ["PLAYGROUND", "PROX_INDEX", "Node", "RealConfig", "TdmNode", "ThymioRobot", "import_tdmclient"]
