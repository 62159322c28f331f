"""Plots, animations and terminal views of a run (matplotlib is imported only when used)."""
