#!/bin/sh
# The Aseba Playground (the Thymio makers' simulator) and a D-Bus daemon for its ground truth:
# tests/test_aseba.py drives it over the Aseba protocol (--backend aseba / playground).
set -e
command -v asebaplayground >/dev/null && command -v dbus-daemon >/dev/null && exit 0
apt-get update -q >/dev/null
apt-get install -y -q --no-install-recommends aseba dbus >/dev/null
