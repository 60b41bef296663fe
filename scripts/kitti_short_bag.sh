#!/usr/bin/env bash
# What kitti.launch gives on a short bag (doc/kitti.md, "A short bag"): the first 160 frames of KITTI 07
# (../shared/data/kitti/07_first160: left grey camera, no poses, no loop inside them) converted by
# kitti_to_bag and played, once the detector and the counter listen, into kitti.launch with the mono detector
# (verification on; no tf, no pose graph, no rviz: the bag has no poses). Prints the decisions by status and
# the loop closures.
# Usage: kitti_short_bag.sh CATKIN_WORKSPACE [more kitti.launch args, e.g. exclusion_window:=20]
set -o pipefail  # no -u: ROS setup scripts read unset variables
ws=${1:?usage: kitti_short_bag.sh CATKIN_WORKSPACE [kitti.launch args...]}
shift
root=$(cd "$(dirname "$0")/.." && pwd)
data=${KITTI_07_FIRST160:-$root/../shared/data/kitti/07_first160}
bag=$root/build/kitti07_first160.bag
export PATH=/usr/bin:/bin:$PATH ROS_HOME=$root/build/ros_home ROS_LOG_DIR=$root/build/ros_home/log
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
[ -f "$bag" ] || rosrun openable_ros kitti_to_bag --sequence "$data" --output "$bag" --quiet || exit 1
port=$((12000 + RANDOM % 1000))
export ROS_MASTER_URI=http://127.0.0.1:$port
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill -INT "$pid" 2> /dev/null; done
  wait 2> /dev/null
  rm -f "${counts:-}"
}
trap cleanup EXIT
roscore -p "$port" > /dev/null 2>&1 & pids+=($!)
sleep 3
# queue_size 200 holds the whole bag: on a busy machine the detector fell more than 10 frames (1 s) behind now
# and then and dropped one (157 to 159 decisions of 160 with two other jobs on the 2 cores).
echo "roslaunch openable_ros kitti.launch bag:=none stereo:=false fixed_frame:=none pose_graph:=false rviz:=false queue_size:=200 $*"
roslaunch openable_ros kitti.launch bag:=none stereo:=false fixed_frame:=none pose_graph:=false rviz:=false \
  queue_size:=200 "$@" > "$root/build/kitti_short_bag.log" 2>&1 & pids+=($!)
counts=$(mktemp)
ROS_NAMESPACE=kitti /usr/bin/python3 "$root/scripts/count_decisions.py" _idle:=8 _timeout:=180 > "$counts" &
counter=$! && pids+=($!)
# The bag is played only once every frame has a listener (a fixed delay may lose the first frame on a busy
# machine): the counter must be registered on /kitti/decisions, and rosbag play waits for the detector's
# subscriptions itself (--wait-for-subscribers on the two topics the mono detector reads).
counter_listens() { rostopic info /kitti/decisions 2> /dev/null | sed -n '/Subscribers:/,$p' | grep -q count_decisions; }
deadline=$((SECONDS + 60))
until counter_listens; do
  [ $SECONDS -lt $deadline ] || { echo "count_decisions did not subscribe to /kitti/decisions within 60 s" >&2; exit 1; }
  sleep 0.2
done
timeout 150 rosbag play --clock --quiet --delay=1 --wait-for-subscribers \
  --topics /kitti/left/image_rect /kitti/left/camera_info --bags="$bag" > "$root/build/kitti_short_bag_play.log" 2>&1 ||
  { echo "rosbag play failed: see $root/build/kitti_short_bag_play.log" >&2; exit 1; }
wait "$counter"
cat "$counts"
