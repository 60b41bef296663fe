#!/usr/bin/env bash
# A soak of the nodes themselves (issue 22): a private roscore on a free port, the MonoDetector standalone
# node (/r1, ~max_history bounded, ~publish_descriptors true) and the PlaceServer standalone node (/server,
# ~max_history bounded, fed by /r1/place_descriptors), FRAMES images published one at a time by
# scripts/node_soak.py, which prints both nodes' RSS and time per frame every EVERY frames (a Markdown table).
#   bash scripts/node_soak.sh build/ws [FRAMES [EVERY [MAX_HISTORY]]]     (defaults 100000 10000 10000)
# `make node_soak` runs it with the defaults. Logs: build/node_soak/.
set -euo pipefail
ws=$(cd "${1:?usage: node_soak.sh CATKIN_WORKSPACE [FRAMES [EVERY [MAX_HISTORY]]]}" && pwd)
frames=${2:-100000}
every=${3:-10000}
max_history=${4:-10000}
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/build/node_soak
mkdir -p "$out"

# Debian's python3 and ROS; a master of our own that no other run shares.
export PATH=/usr/bin:/bin:$PATH
set +u
source "$ws/devel/setup.bash"
set -u
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_HOSTNAME=127.0.0.1
export ROS_HOME=$out/ros_home ROS_LOG_DIR=$out/ros_home/log

pids=()
cleanup()
{
  for pid in "${pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  wait 2>/dev/null || true
}
trap cleanup EXIT

roscore -p "$port" >"$out/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  rostopic list >/dev/null 2>&1 && break
  sleep 0.2
done
rostopic list >/dev/null 2>&1 || { echo "node_soak: roscore on port $port did not start (see $out/roscore.log)"; exit 1; }

bin=$ws/devel/lib/openable_ros
"$bin/mono_detector_node" __ns:=/r1 __name:=detector _max_history:="$max_history" _publish_descriptors:=true \
  _queue_size:=10 >"$out/detector.log" 2>&1 &
detector_pid=$!
pids+=($detector_pid)
rosparam set /server/place_server/robots "[r1]"  # a list: the command line's _name:=value gives strings only
"$bin/place_server_node" __ns:=/server __name:=place_server _max_history:="$max_history" \
  r1/place_descriptors:=/r1/place_descriptors >"$out/place_server.log" 2>&1 &
server_pid=$!
pids+=($server_pid)
for _ in $(seq 100); do
  rostopic info /r1/image 2>/dev/null | grep -q detector && break
  sleep 0.2
done

echo "node soak: $frames frames, max_history $max_history, master $ROS_MASTER_URI; detector pid $detector_pid," \
  "place server pid $server_pid"
started=$(date +%s)
status=0
/usr/bin/python3 "$root/scripts/node_soak.py" "$frames" "$every" "$detector_pid" "$server_pid" | tee "$out/table.md" ||
  status=$?
echo "node soak: $(($(date +%s) - started)) s; the nodes' warnings: $(grep -c WARN "$out/detector.log" || true)" \
  "(detector), $(grep -c WARN "$out/place_server.log" || true) (place server)"
kill -0 "$detector_pid" 2>/dev/null || { echo "node soak: the detector died"; status=1; }
kill -0 "$server_pid" 2>/dev/null || { echo "node soak: the place server died"; status=1; }
exit $status
