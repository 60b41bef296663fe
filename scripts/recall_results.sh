#!/usr/bin/env bash
# The table of doc/results.md "Where the recall goes (issue 21)": the streams of issue 21 with each shipped
# configuration made for them, at the first pass's pace, faster, slower and with stops
# (scripts/pace_eval.py), published / wrong / precision / recall and the statuses of the frames that have a
# true loop and got none (decisions.csv).
#
#   scripts/recall_results.sh [--bin DIR] [--out DIR] [--jobs N]
#
# Needs ../shared/data beside the package. About 10 minutes on a 2-core machine. Prints Markdown on stdout.
set -euo pipefail
out=/tmp/openable_recall_results
usage=2,9p
# shellcheck source=scripts/pace_tables_common.sh
source "$(dirname "${BASH_SOURCE[0]}")/pace_tables_common.sh"

echo "| stream | config | pace | published / wrong / precision / recall | frames with a true loop and none: status |"
echo "|---|---|---|---|---|"
run() {  # name first second tolerance config [pace_eval options...]
  local name=$1 first=$2 second=$3 tolerance=$4 config=$5
  shift 5
  python3 "$here/scripts/pace_eval.py" --bin "$bin" --jobs "$jobs" --markdown --misses --first "$first" \
    --second "$second" --tolerance "$tolerance" --config "$here/config/$config.yaml" \
    --out "$out/$config/$(echo "$name" | tr -c 'A-Za-z0-9\n' _)" "$@" |
    sed "s/^| /| $name | $config | /"
}
paces=(--profile 1x --profile 2x --profile 0.5x --profile stops:100)
for config in default gardens_point; do
  run "GP day_right then day_left" "$gp/day_right" "$gp/day_left" 2 "$config" "${paces[@]}"
  run "GP day_right then night_right" "$gp/day_right" "$gp/night_right" 2 "$config" "${paces[@]}"
  run "GP day_left then night_right" "$gp/day_left" "$gp/night_right" 2 "$config" "${paces[@]}"
  run "GP short route, day_right 0-59 then day_left 0-59" "$gp/day_right" "$gp/day_left" 2 "$config" --frames 60 --profile 1x
  run "GP short route, day_right 0-59 then night_right 0-59" "$gp/day_right" "$gp/night_right" 2 "$config" --frames 60 --profile 1x
done
run "Nordland summer then winter" "$nl/summer" "$nl/winter" 1 nordland "${paces[@]}"
