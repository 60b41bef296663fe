#!/usr/bin/env bash
# The demo: the bundled Gardens Point sample (day_right = the map, night_right = the query, same places by
# frame number) through openable_offline, with the configuration recommended for Gardens Point.
set -euo pipefail
ws=${1:?usage: demo.sh CATKIN_WORKSPACE}
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/build/demo
bin=$ws/devel/lib/openable_ros/openable_offline

echo "openable_ros demo: Gardens Point day (map) vs night (query), 200 + 200 real frames (data/sample)"
"$bin" --config "$root/config/gardens_point.yaml" \
  --reference "$root/data/sample/day_right" --query "$root/data/sample/night_right" \
  --output "$out" --ground-truth-tolerance 2
echo
echo "first accepted loop closures (query frame, matched map frame, normalised distance):"
head -n 6 "$out/loop_closures.csv" | column -t -s,
echo
echo "look at: $out/distance_matrix.png (the magenta diagonal: each night frame matched with its day twin)"
