#!/bin/sh
# Debian's Chromium loads every page of `thymio-bt grade --html` headless (tests/test_grade_site.py):
# no console error, no failed or off-machine request, the DOM, screenshots. A font for the screenshots.
set -e
command -v chromium >/dev/null && exit 0
export DEBIAN_FRONTEND=noninteractive
apt-get update -q >/dev/null
apt-get install -y -q --no-install-recommends chromium fonts-dejavu-core >/dev/null
