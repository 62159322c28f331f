#!/usr/bin/env bash
# Gradescope runs this once, when it builds the autograder's image (Ubuntu): it installs thymio-bt.
# Zip this folder's files with the course's assignment.yaml (and the worlds it names, and secret.txt
# when its hidden worlds draw a secret seed) and upload the zip as the autograder.
set -euo pipefail
apt-get update
apt-get install -y --no-install-recommends python3 python3-venv
python3 -m venv /opt/thymio-bt
/opt/thymio-bt/bin/pip install --quiet thymio-bt
