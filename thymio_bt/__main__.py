"""``python -m thymio_bt``: the same command line as ``thymio-bt``."""

from .cli import main

main(prog_name="thymio-bt")
