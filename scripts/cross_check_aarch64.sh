#!/usr/bin/env bash
# Builds the Hamming kernels (src/core/hamming) and their test (test/core/test_hamming.cpp) for aarch64 without
# ROS or OpenCV, and runs the test under qemu-user when it is installed (natively on an aarch64 host). Checks
# that the x86 kernel files compile to nothing there and that the test ran the portable and NEON kernels.
# Needs g++-aarch64-linux-gnu (and qemu-user to run; scripts/install_deps.sh installs both when it can) and
# googletest's sources in /usr/src/googletest (libgtest-dev). Output in build/cross_aarch64.
# Exit status: 0 passed (built and, with qemu or on aarch64, ran), 1 failed, 77 skipped (no aarch64 compiler).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/build/cross_aarch64
gtest=${GTEST_SOURCE_DIR:-/usr/src/googletest/googletest}
start=$SECONDS

if [ "$(uname -m)" = aarch64 ]; then
  cxx=${CXX:-g++}
  nm=nm
  run=()
else
  cxx=aarch64-linux-gnu-g++
  nm=aarch64-linux-gnu-nm
  run=()
  for q in qemu-aarch64 qemu-aarch64-static; do
    if command -v "$q" > /dev/null; then
      run=("$q")
      break
    fi
  done
fi
if ! command -v "$cxx" > /dev/null; then
  echo "cross_check_aarch64: skipped, no $cxx (apt-get install g++-aarch64-linux-gnu)"
  exit 77
fi
if [ ! -f "$gtest/src/gtest-all.cc" ]; then
  echo "cross_check_aarch64: failed, no googletest sources in $gtest (apt-get install libgtest-dev)"
  exit 1
fi
mkdir -p "$out"
flags=(-std=c++17 -O2 -static -pthread)

# googletest, once: it is the slow part (about a minute) and never changes.
for unit in gtest-all gtest_main; do
  if [ ! -f "$out/$unit.o" ] || [ "$gtest/src/$unit.cc" -nt "$out/$unit.o" ]; then
    "$cxx" "${flags[@]}" -I"$gtest/include" -I"$gtest" -c "$gtest/src/$unit.cc" -o "$out/$unit.o"
  fi
done

# The Hamming sources and their test, warnings as errors.
objects=()
for source in "$root"/src/core/hamming/*.cpp "$root/test/core/test_hamming.cpp"; do
  object=$out/$(basename "$source" .cpp).o
  "$cxx" "${flags[@]}" -Wall -Wextra -Werror -I"$root/include" -I"$root/src/core" -I"$gtest/include" -c "$source" -o "$object"
  objects+=("$object")
done
for x86 in hamming_x86 hamming_avx512; do
  if [ -n "$("$nm" "$out/$x86.o")" ]; then
    echo "cross_check_aarch64: failed, $x86.cpp is not empty on aarch64 (its x86 guard):"
    "$nm" "$out/$x86.o" | head -n 5
    exit 1
  fi
done
# (googletest's socket code makes ld warn about getaddrinfo in a static binary: shown only if linking fails)
if ! "$cxx" "${flags[@]}" "${objects[@]}" "$out/gtest-all.o" "$out/gtest_main.o" -o "$out/test_hamming" \
  2> "$out/link.log"; then
  cat "$out/link.log"
  echo "cross_check_aarch64: failed to link"
  exit 1
fi
echo "cross_check_aarch64: built $out/test_hamming with $cxx in $((SECONDS - start)) s"

if [ "$(uname -m)" != aarch64 ] && [ ${#run[@]} -eq 0 ]; then
  echo "cross_check_aarch64: passed (built only: no qemu-aarch64 to run it; apt-get install qemu-user)"
  exit 0
fi
if OPENABLE_EXPECT_HAMMING_KERNELS="portable neon" "${run[@]}" "$out/test_hamming" \
  --gtest_output="xml:$out/test_hamming.xml" > "$out/test_hamming.log" 2>&1; then
  echo "cross_check_aarch64: $(grep -m 1 "Hamming kernels exercised" "$out/test_hamming.log")"
  echo "cross_check_aarch64: passed ($(grep -E "^\[  PASSED  \]" "$out/test_hamming.log"), ${run[*]:-native}," \
    "$((SECONDS - start)) s in all)"
else
  log_lines=$(grep -E "Failure|FAILED|Expected|Which is|error" "$out/test_hamming.log" | head -n 40)
  echo "${log_lines:-$(tail -n 40 "$out/test_hamming.log")}"
  echo "cross_check_aarch64: failed (test_hamming under ${run[*]:-native}; see $out/test_hamming.log)"
  exit 1
fi
