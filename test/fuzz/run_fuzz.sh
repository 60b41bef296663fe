#!/usr/bin/env bash
# Builds the libFuzzer targets of test/fuzz with clang (ASan + UBSan) in build/fuzz and runs each for
# FUZZ_SECONDS (default 60). Starts from the committed corpus test/fuzz/corpus/<target> (seeds and every
# input that once found a bug) plus what earlier runs found (build/fuzz/corpus/<target>). A finding is kept
# as build/fuzz/artifacts/<target>/crash-* and makes the script exit non-zero; copy it into
# test/fuzz/corpus/<target>/ once fixed, so `make test` replays it (test_fuzz_corpus).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$root/build/fuzz
seconds=${FUZZ_SECONDS:-60}
jobs=${JOBS:-1}
targets=${FUZZ_TARGETS:-map_loader config_yaml npy place_messages detector_image}

cmake -S "$root/test/fuzz" -B "$out/build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$out/build" -j "$jobs" -- --no-print-directory

failed=0
for target in $targets; do
  mkdir -p "$out/corpus/$target" "$out/artifacts/$target"
  echo "fuzz: $target for ${seconds} s"
  # -rss_limit_mb: a loader that allocates more than this for a small input is a finding too.
  if ! ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1 \
      "$out/build/fuzz_$target" -max_total_time="$seconds" -rss_limit_mb=2048 -max_len=65536 -timeout=10 \
      -print_final_stats=1 -artifact_prefix="$out/artifacts/$target/" \
      "$out/corpus/$target" "$root/test/fuzz/corpus/$target" 2>"$out/$target.log"; then
    failed=1
    echo "fuzz: $target FOUND A PROBLEM:"
    grep -E "ERROR|runtime error|==ERROR|Test unit written|SUMMARY" "$out/$target.log" | head -n 10
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "$out/$target.log" | tail -n 3
done
exit $failed
