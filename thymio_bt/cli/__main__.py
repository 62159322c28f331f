"""``python -m thymio_bt.cli``: the same command line as ``thymio-bt``."""

from thymio_bt.cli import main

main(prog_name="thymio-bt")
