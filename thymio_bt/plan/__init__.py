"""A mission as data (no py_trees object, no robot), and the node kinds it may name."""
