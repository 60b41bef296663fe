#!/usr/bin/env bash
# The table of doc/results.md "Sessions: a map continued": a traversal saved as a map, the next one continued
# into it as a new session (openable_offline --map-out, then --map-in), scored as the joined stream
# (openable_eval --joined). Prints Markdown rows: config | streams | published | wrong | precision | recall.
#
#   scripts/session_results.sh [--bin DIR] [--out DIR]
#
# Needs ../shared/data beside the package. A few minutes on a 2-core machine.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$here/build/ws/devel/lib/openable_ros"
out=/tmp/openable_session_results
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    -h|--help) sed -n 2,8p "$0"; exit 0 ;;
    *) echo "unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
data="$here/../shared/data"
[[ -d "$data/gardens_point" && -d "$data/nordland" ]] || { echo "no ../shared/data beside the package" >&2; exit 1; }

row() {  # config name first second tolerance
  local config=$1 name=$2 first=$3 second=$4 tolerance=$5
  local dir="$out/$config/$(echo "$name" | tr -c 'A-Za-z0-9\n' _)"
  rm -rf "$dir" && mkdir -p "$dir"
  "$bin/openable_offline" --quiet --config "$here/config/$config.yaml" --reference "$first" --output "$dir/first" \
    --map-out "$dir/first.map" > /dev/null
  "$bin/openable_offline" --quiet --config "$here/config/$config.yaml" --reference "$second" --output "$dir/second" \
    --map-in "$dir/first.map" > /dev/null
  local n
  n=$(find "$first" -maxdepth 1 -type f | wc -l)
  "$bin/openable_eval" --published "$dir/second/loop_closures.csv" --decisions "$dir/second/decisions.csv" \
    --joined "$n" --tolerance "$tolerance" \
    --output "$dir/eval" > "$dir/eval.txt"
  python3 - "$dir/eval/metrics.json" "$config" "$name" << 'EOF'
import json, sys
m = json.load(open(sys.argv[1]))
p = m
print(f"| {sys.argv[2]}.yaml | {sys.argv[3]} | {p['published']} | {p['wrong']} | {p['precision']:.3f} | {p['recall']:.3f} |")
EOF
}

gp="$data/gardens_point"
nl="$data/nordland"
echo "| config | map, then continued | published | wrong | precision | recall |"
echo "|---|---|---|---|---|---|"
row default "Gardens Point day_right, then night_right" "$gp/day_right" "$gp/night_right" 2
row gardens_point "Gardens Point day_right, then night_right" "$gp/day_right" "$gp/night_right" 2
row default "Nordland summer, then winter" "$nl/summer" "$nl/winter" 1
row nordland "Nordland summer, then winter" "$nl/summer" "$nl/winter" 1
