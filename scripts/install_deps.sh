#!/usr/bin/env bash
# Installs the Debian packages openable_ros needs to build, test and run the demo.
# Runs apt-get update once, and only when something is missing.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  catkin ros-base-dev ros-message-generation libnodeletlib-dev pluginlib-dev libcv-bridge-dev
  libimage-transport-dev libmessage-filters-dev libtf2-ros-dev libtf2-geometry-msgs-dev librosbag-dev
  librostest-dev python3-rostest python3-roslaunch python3-rosmaster python3-rosbag rosbash rosout
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  python3-sensor-msgs python3-std-msgs python3-geometry-msgs python3-nav-msgs python3-stereo-msgs
  python3-visualization-msgs python3-diagnostic-msgs python3-tf2-msgs python3-std-srvs python3-numpy
  libsensor-msgs-dev libstereo-msgs-dev libnav-msgs-dev libvisualization-msgs-dev libdiagnostic-msgs-dev
  libgeometry-msgs-dev libstd-srvs-dev libtf2-msgs-dev libdiagnostic-updater-dev
  libopencv-dev libyaml-cpp-dev libeigen3-dev libceres-dev libgtest-dev libbenchmark-dev
  # stereo_image_proc for the rostest of the disparity pipeline (issue 13); -dev holds its package.xml
  ros-stereo-image-proc libstereo-image-proc-dev
  # rviz: the launch files start it (and roslaunch-check of launch/kitti.launch needs it installed)
  rviz
)

# Optional: the aarch64 cross check of the Hamming kernels (scripts/cross_check_aarch64.sh, one more test of
# run_tests.sh when the compiler is there; about 25 s and 110 MB to install on x86-64) and clang for the short
# fuzz run of run_tests.sh (libFuzzer, test/fuzz/run_fuzz.sh). When they cannot be installed those checks are
# skipped, nothing fails.
optional=(clang)
[ "$(uname -m)" = x86_64 ] && optional+=(g++-aarch64-linux-gnu qemu-user)

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
missing=()
for p in "${packages[@]}"; do
  installed "$p" || missing+=("$p")
done
missing_optional=()
for p in "${optional[@]}"; do
  installed "$p" || missing_optional+=("$p")
done
if [ ${#missing[@]} -eq 0 ] && [ ${#missing_optional[@]} -eq 0 ]; then
  echo "install_deps: all $((${#packages[@]} + ${#optional[@]})) Debian packages already installed"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
if [ ${#missing[@]} -gt 0 ]; then
  echo "install_deps: installing ${#missing[@]} missing packages: ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if [ ${#missing_optional[@]} -gt 0 ]; then
  echo "install_deps: installing ${#missing_optional[@]} optional packages: ${missing_optional[*]}"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing_optional[@]}" \
    >/dev/null || echo "install_deps: could not install ${missing_optional[*]}: the aarch64 cross check or the fuzz run is skipped"
fi
echo "install_deps: done"
