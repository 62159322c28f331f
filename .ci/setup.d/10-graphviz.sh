#!/bin/sh
# Graphviz's dot program draws `thymio-bt tree --svg/--png` (tests/test_viz.py).
set -e
command -v dot >/dev/null && exit 0
apt-get update -q >/dev/null
apt-get install -y -q --no-install-recommends graphviz >/dev/null
