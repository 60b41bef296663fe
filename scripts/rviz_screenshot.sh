#!/usr/bin/env bash
# A headless screenshot of rviz with rviz/openable.rviz while mono.launch (config/default.yaml, as shipped)
# runs on the bundled Gardens Point sample: day_right then night_right published live at 10 Hz by
# scripts/publish_sample.py, with a made-up path on tf (fixed_frame odom) so loop_markers has poses.
# Needs Xvfb, ImageMagick's import and python3-opencv (apt-get install xvfb imagemagick python3-opencv
# python3-tf2-ros). Usage: rviz_screenshot.sh CATKIN_WORKSPACE OUT.png [WIDTHxHEIGHT]
set -o pipefail  # no -u: ROS setup scripts read unset variables
ws=${1:?usage: rviz_screenshot.sh CATKIN_WORKSPACE OUT.png [WIDTHxHEIGHT]}
out=$(realpath -m "${2:?usage: rviz_screenshot.sh CATKIN_WORKSPACE OUT.png [WIDTHxHEIGHT]}")
size=${3:-1500x900}
root=$(cd "$(dirname "$0")/.." && pwd)
export PATH=/usr/bin:/bin:$PATH ROS_HOME=$root/build/ros_home ROS_LOG_DIR=$root/build/ros_home/log
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
display=:$((90 + RANDOM % 100))
port=$((12000 + RANDOM % 1000))
export ROS_MASTER_URI=http://127.0.0.1:$port DISPLAY=$display LIBGL_ALWAYS_SOFTWARE=1
pids=()
cleanup() { for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null; done; wait 2> /dev/null; }
trap cleanup EXIT
Xvfb "$display" -screen 0 "${size}x24" -nolisten tcp > /dev/null 2>&1 & pids+=($!)
roscore -p "$port" > /dev/null 2>&1 & pids+=($!)
sleep 3
roslaunch openable_ros mono.launch image:=/camera/image_raw fixed_frame:=odom rviz:=true \
  > "$root/build/rviz_screenshot.log" 2>&1 & pids+=($!)
sleep 8  # rviz up and subscribed
/usr/bin/python3 "$root/scripts/publish_sample.py" || exit 1
sleep 4  # last distance_matrix (~matrix_rate 2 Hz) and markers drawn
import -display "$display" -window root "$out" && echo "wrote $out"
