#!/usr/bin/env bash
# Runs openable_bench and prints the performance table of doc/performance.md from that one run.
set -euo pipefail
ws=${1:?usage: bench.sh CATKIN_WORKSPACE [benchmark args]}
shift
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/build/bench.json
"$ws/devel/lib/openable_ros/openable_bench" --benchmark_out="$out" --benchmark_out_format=json \
  --benchmark_min_time=0.5 "$@"
python3 "$root/scripts/bench_table.py" "$out"
