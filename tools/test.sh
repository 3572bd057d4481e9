#!/usr/bin/env bash
# The test command: installs what it needs, builds, and runs the whole suite
# twice: optimised, then under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

tools/deps.sh build storage dds render hil fuzz

run_suite() {  # run_suite BUILD_DIR [cmake options...]
  local dir=$1
  shift
  echo "== configure and build: $dir $*"
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
  echo "== tests: $dir"
  ctest --test-dir "$dir" --output-on-failure -j "$jobs"
}

run_suite build
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  run_suite build-asan -DVISVOL_SANITIZE=ON
tools/fuzz.sh
echo "== all tests passed (optimised, ASan+UBSan, fuzzing)"
