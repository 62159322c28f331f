"""thymio-bt: YAML behaviour-tree missions for a simulated (and real) Thymio II."""

from thymio_bt import _moved

__version__ = "0.1.0"
__all__ = ["__version__"]

_moved.install()
