"""thymio-bt: YAML behaviour-tree missions for a simulated (and real) Thymio II."""

__version__ = "0.1.0"
