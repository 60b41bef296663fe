#!/usr/bin/env bash
# The demo: the main job of the package on the bundled Gardens Point sample (data/sample): one stream that
# revisits itself, day_right then night_right (frame 200 + i is the place of frame i; the first 200 frames
# have no loop), through openable_offline with config/default.yaml, the published set scored by openable_eval.
set -euo pipefail
ws=${1:?usage: demo.sh CATKIN_WORKSPACE}
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/build/demo
bin=$ws/devel/lib/openable_ros

echo "openable_ros demo: loop closure in one stream, Gardens Point day then night, 200 + 200 real frames (data/sample)"
rm -rf "$out/stream"
mkdir -p "$out/stream"
i=0
for image in "$root"/data/sample/day_right/*.jpg "$root"/data/sample/night_right/*.jpg; do
  ln -s "$image" "$out/stream/$(printf 'frame%04d.jpg' "$i")"
  i=$((i + 1))
done
"$bin/openable_offline" --config "$root/config/default.yaml" --reference "$out/stream" --output "$out"
echo
echo "scored against the ground truth (openable_eval --joined 200 --tolerance 2):"
"$bin/openable_eval" --published "$out/loop_closures.csv" --decisions "$out/decisions.csv" --joined 200 \
  --tolerance 2 --output "$out/eval" --title "config/default.yaml, Gardens Point day then night" | head -n 4
echo
echo "first published loop closures (query frame, matched frame, normalised distance, score, status):"
head -n 6 "$out/loop_closures.csv" | column -t -s,
echo
echo "look at: $out/distance_matrix.png (the magenta line in the lower half: night frames meeting their day twins)"
echo "         $out/eval/published_pr.png (precision-recall over the decision score)"
