#!/usr/bin/env bash
# The tables of doc/results.md "Loops at any pace": every shipped configuration on real streams of two
# traversals, the second driven at another pace (scripts/pace_eval.py), published / wrong / precision / recall.
#
#   scripts/pace_results.sh [--bin DIR] [--out DIR] [--jobs N]
#
# Needs ../shared/data beside the package. About 10 minutes on a 2-core machine. Prints Markdown on stdout.
set -euo pipefail
out=/tmp/openable_pace_results
usage=2,7p
# shellcheck source=scripts/pace_tables_common.sh
source "$(dirname "${BASH_SOURCE[0]}")/pace_tables_common.sh"
profiles=(1x 2x 3x 0.5x 0.33x stops:25 stops:100 stops:200 varying:100 ramp:0.5,2 random:1 1.25x 1.8x 2.5x)
args=()
for p in "${profiles[@]}"; do args+=(--profile "$p"); done

run() {  # name first second tolerance config [first-profile]
  local name=$1 first=$2 second=$3 tolerance=$4 config=$5 first_profile=${6:-1x}
  echo
  echo "**$name**, config/$config.yaml (published / wrong / precision / recall):"
  echo
  echo "| second traversal | published / wrong / precision / recall |"
  echo "|---|---|"
  python3 "$here/scripts/pace_eval.py" --bin "$bin" --jobs "$jobs" --markdown --first "$first" --second "$second" \
    --first-profile "$first_profile" --tolerance "$tolerance" --config "$here/config/$config.yaml" \
    --out "$out/$config/$(echo "$name" | tr -c 'A-Za-z0-9\n' _)" "${args[@]}"
}

for config in default gardens_point nordland; do
  run "Gardens Point day_right then night_right" "$gp/day_right" "$gp/night_right" 2 "$config"
  run "Nordland summer then winter" "$nl/summer" "$nl/winter" 1 "$config"
done
# Pairings and orders not tuned on.
run "Gardens Point day_right then day_left" "$gp/day_right" "$gp/day_left" 2 default
run "Gardens Point night_right then day_left" "$gp/night_right" "$gp/day_left" 2 default
run "Nordland winter then summer" "$nl/winter" "$nl/summer" 1 default
run "Gardens Point day_right at 2x, then night_right" "$gp/day_right" "$gp/night_right" 2 default 2x
