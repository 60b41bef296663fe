# Sourced by scripts/pace_results.sh and scripts/recall_results.sh (both print tables of doc/results.md from
# scripts/pace_eval.py runs): their options --bin DIR, --out DIR, --jobs N, --help, and the shared data.
# The caller sets `out` (its default work folder) and `usage` (the lines of its header to print for --help).
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$here/build/ws/devel/lib/openable_ros"
jobs=2
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    -h|--help) sed -n "$usage" "$0"; exit 0 ;;
    *) echo "unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
data="$here/../shared/data"
[[ -d "$data/gardens_point" && -d "$data/nordland" ]] || { echo "no ../shared/data beside the package" >&2; exit 1; }
gp="$data/gardens_point"
nl="$data/nordland"
