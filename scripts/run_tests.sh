#!/usr/bin/env bash
# Runs every registered test of the package (gtest without a master, rostest with its own master) in the
# catkin workspace, prints the failures and catkin_test_results' summary, and ends with the plain line
# "N passed, N failed". Exits non-zero when a test failed, errored or did not produce a result.
set -o pipefail  # no -u: ROS setup scripts read unset variables
ws=$(cd "${1:?usage: run_tests.sh CATKIN_WORKSPACE}" && pwd)
root=$(cd "$(dirname "$0")/.." && pwd)
log=$root/build/run_tests.log
export PATH=/usr/bin:/bin:$PATH ROS_HOME=$root/build/ros_home ROS_LOG_DIR=$root/build/ros_home/log
cd "$ws"
# shellcheck disable=SC1091
source devel/setup.bash
rm -rf build/test_results
catkin_make run_tests -j1 -DPYTHON_EXECUTABLE=/usr/bin/python3 > "$log" 2>&1
run_rc=$?

# gtest's own lines for anything that failed, so the reason is on screen, not only in the log.
grep -E "^\[  FAILED  \]|Failure$|^/.*:[0-9]+: Failure|FAILURE|\[ROSTEST\]|Error" "$log" | sort -u | head -n 60

summary=$(catkin_test_results build/test_results 2>&1)
results_rc=$?
echo "$summary" | grep -vE "^Skipping" | tail -n 30
line=$(echo "$summary" | grep -E "^Summary:" | tail -n 1)
tests=$(echo "$line" | sed -E 's/.* ([0-9]+) tests.*/\1/')
errors=$(echo "$line" | sed -E 's/.* ([0-9]+) errors.*/\1/')
failures=$(echo "$line" | sed -E 's/.* ([0-9]+) failures.*/\1/')
if [ -z "$line" ] || [ "$tests" = "0" ]; then
  echo "no test results found (see $log)"
  echo "0 passed, 1 failed"
  exit 1
fi
failed=$((errors + failures))
if [ $run_rc -ne 0 ] && [ $failed -eq 0 ]; then
  echo "catkin_make run_tests failed without a failing test result (a test did not build or run; see $log)"
  failed=1
fi

# The checks below are one test each, added to catkin_test_results' counts: `count_check RC` after each.
count_check() {
  tests=$((tests + 1))
  if [ "$1" -ne 0 ]; then
    failures=$((failures + 1))
    failed=$((failed + 1))
  fi
}

# One more test: the numbers README.md, doc/ros_api.md and doc/kitti.md quote from runs against this run's:
# the properties the tests recorded in their results, the demo's output and what kitti.launch decides on a
# 160-frame KITTI bag (scripts/kitti_short_bag.sh, as shipped and with exclusion_window:=20); the check is
# test/docs/check_doc_numbers.py.
docs_log=$root/build/doc_numbers.log
{
  bash "$root/scripts/demo.sh" "$ws" > "$root/build/demo.log" 2>&1 || echo "scripts/demo.sh failed: see $root/build/demo.log"
  bash "$root/scripts/kitti_short_bag.sh" "$ws" > "$root/build/kitti160.log" 2>&1 ||
    echo "scripts/kitti_short_bag.sh failed: see $root/build/kitti160.log"
  bash "$root/scripts/kitti_short_bag.sh" "$ws" exclusion_window:=20 > "$root/build/kitti160_ew20.log" 2>&1 ||
    echo "scripts/kitti_short_bag.sh exclusion_window:=20 failed: see $root/build/kitti160_ew20.log"
  python3 "$root/test/docs/check_doc_numbers.py" --self-test &&
    python3 "$root/test/docs/check_doc_numbers.py" --results build/test_results/openable_ros \
      --output demo="$root/build/demo.log" --output kitti160="$root/build/kitti160.log" \
      --output kitti160_ew20="$root/build/kitti160_ew20.log" \
      "$root/README.md" "$root/doc/ros_api.md" "$root/doc/kitti.md"
} > "$docs_log" 2>&1
docs_rc=$?
count_check $docs_rc
if [ $docs_rc -eq 0 ]; then
  tail -n 1 "$docs_log"
else
  tail -n 40 "$docs_log"
fi

# One more test where an aarch64 compiler is installed (install_deps.sh): the Hamming kernels and their test
# built for aarch64 without ROS, run under qemu-user (scripts/cross_check_aarch64.sh, output in build/).
if command -v aarch64-linux-gnu-g++ > /dev/null || [ "$(uname -m)" = aarch64 ]; then
  cross_log=$root/build/cross_check_aarch64.log
  bash "$root/scripts/cross_check_aarch64.sh" > "$cross_log" 2>&1
  cross_rc=$?
  if [ $cross_rc -ne 77 ]; then
    count_check $cross_rc
    if [ $cross_rc -eq 0 ]; then
      tail -n 1 "$cross_log"
    else
      tail -n 20 "$cross_log"
    fi
  fi
fi

# One more test where clang is installed (install_deps.sh): every libFuzzer target (test/fuzz: the map, the
# configuration YAML, .npy, the place messages, the detector's images) built with ASan + UBSan and run for
# FUZZ_SECONDS (default 10) from the committed corpus; a finding fails it (test/fuzz/run_fuzz.sh, output in build/).
if command -v clang++ > /dev/null; then
  fuzz_log=$root/build/fuzz.log
  FUZZ_SECONDS=${FUZZ_SECONDS:-10} JOBS=$(nproc) bash "$root/test/fuzz/run_fuzz.sh" > "$fuzz_log" 2>&1
  fuzz_rc=$?
  count_check $fuzz_rc
  if [ $fuzz_rc -eq 0 ]; then
    echo "fuzz: $(grep -c '^fuzz: .* for ' "$fuzz_log") targets, ${FUZZ_SECONDS:-10} s each, no finding" \
      "($(grep -h 'stat::number_of_executed_units' "$fuzz_log" | awk '{s += $2} END {print s + 0}') inputs)"
  else
    tail -n 30 "$fuzz_log"
  fi
fi

# One more test: no header outside the C/C++ library, OpenCV, yaml-cpp, Eigen, Ceres and the core's own
# reached the core's objects (ROS's headers share /usr/include on Debian, so no include path can keep them out).
python3 "$root/scripts/check_core_ros_free.py" "$PWD"
count_check $?
echo "$((tests - errors - failures)) passed, $failed failed"
[ $failed -eq 0 ] && [ $results_rc -eq 0 ]
