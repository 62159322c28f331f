#!/bin/sh
# socat bridges a pseudo-terminal to the Aseba Playground's TCP port, so the aseba backend's serial
# path (a USB Thymio's) runs in CI (tests/test_serial_path.py).
set -e
command -v socat >/dev/null && exit 0
apt-get update -q >/dev/null
apt-get install -y -q --no-install-recommends socat >/dev/null
