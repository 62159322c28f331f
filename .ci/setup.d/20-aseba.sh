#!/bin/sh
# The Aseba Playground (the Thymio makers' simulator) and a D-Bus daemon for its ground truth:
# tests/test_aseba.py drives it over the Aseba protocol (--backend aseba / playground). g++ and
# Enki's headers build the correction of Enki 1.6.99's stale sensor rays (backends/playground/enki_fix.py).
set -e
command -v asebaplayground >/dev/null && command -v dbus-daemon >/dev/null && command -v g++ >/dev/null \
    && [ -e /usr/include/enki/interactions/IRSensor.h ] && exit 0
apt-get update -q >/dev/null
apt-get install -y -q --no-install-recommends aseba dbus g++ libenki-dev >/dev/null
