#!/usr/bin/env bash
# The test command: installs what it needs, builds, and runs the whole suite
# twice (optimised, then under AddressSanitizer + UndefinedBehaviorSanitizer,
# less the long numerical runs labelled `numeric`), the threaded tests under
# ThreadSanitizer, then the fuzzers. Prints each
# stage's time as it ends and all of them at the end, passed or not.
#   VISVOL_FUZZ_SECONDS   time per fuzz target (default here 10: the seed corpus
#                         replayed and a short run; tools/fuzz.sh alone runs 60)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

stage_names=()
stage_seconds=()
started=$SECONDS

report_times() {
  local status=$?
  echo "== stage times (2 cores: $(nproc))"
  local i
  for i in "${!stage_names[@]}"; do
    printf '   %-36s %4d s\n' "${stage_names[$i]}" "${stage_seconds[$i]}"
  done
  printf '   %-36s %4d s (%d min)\n' "total" $((SECONDS - started)) $(((SECONDS - started + 59) / 60))
  return $status
}
trap report_times EXIT

# stage NAME COMMAND...: runs COMMAND and records how long it took.
stage() {
  local name=$1
  shift
  local t0=$SECONDS
  echo "== $name"
  "$@"
  stage_names+=("$name")
  stage_seconds+=($((SECONDS - t0)))
  echo "== $name: $((SECONDS - t0)) s"
}

# Line tables only (-g1: stack traces without the variables, half the
# compile time of -g); Ninja for a new tree. The benchmarks are built once, in
# the optimised tree.
build_tree() {  # build_tree BUILD_DIR [cmake options...] [-- targets...]
  local dir=$1
  shift
  local options=() targets=()
  while (($#)); do
    if [[ $1 == -- ]]; then
      shift
      targets=(--target "$@")
      break
    fi
    options+=("$1")
    shift
  done
  local generator=()
  [[ -f "$dir/CMakeCache.txt" ]] || generator=(-G Ninja)
  cmake "${generator[@]}" -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVISVOL_DEBUG_INFO=-g1 \
    "${options[@]}" >/dev/null
  cmake --build "$dir" -j "$jobs" "${targets[@]}"
}


# The packages only the VM test and the fuzzers need (qemu, a kernel, clang:
# about half of what a fresh machine downloads) are installed beside the
# optimised tree's build and tests, which need none of them (that tree runs
# no VM: the ASan+UBSan tree runs the same suite in it).
late_log=$(mktemp)
wait_for_late_packages() {
  local rc=0
  wait "$late_install" || rc=$?
  cat "$late_log"
  rm -f "$late_log"
  ((rc == 0)) || echo "== installing the VM and fuzzer packages failed (exit $rc)" >&2
  return $rc
}

export VISVOL_FUZZ_SECONDS=${VISVOL_FUZZ_SECONDS:-10}
stage "install packages" tools/deps.sh build storage dds render
tools/deps.sh hil fuzz >"$late_log" 2>&1 &
late_install=$!
stage "build: optimised" build_tree build -DVISVOL_HIL_QEMU=OFF
stage "tests: optimised" ctest --test-dir build --output-on-failure -j "$jobs"
stage "install: VM + fuzz packages" wait_for_late_packages
stage "build: ASan+UBSan" build_tree build-asan -DVISVOL_SANITIZE=ON -DVISVOL_BUILD_BENCHMARKS=OFF
stage "tests: ASan+UBSan" env ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --test-dir build-asan --output-on-failure -j "$jobs" \
  -LE numeric
# The tests labelled `threaded` (ctest -L threaded; target visvol_threaded_tests):
# real threads sharing state (hand-offs, the loop, the executive, the hull
# builder, the tile pager, the DDS publisher and intake, the renderer and the
# flyable-path threads), under ThreadSanitizer.
stage "build: TSan (threaded tests)" build_tree build-tsan -DVISVOL_TSAN=ON -DVISVOL_BUILD_BENCHMARKS=OFF \
  -- visvol_threaded_tests
stage "tests: TSan" env TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp" \
  ctest --test-dir build-tsan -L threaded -LE numeric --output-on-failure -j "$jobs"
stage "fuzzing: build and run" tools/fuzz.sh
echo "== all tests passed (optimised, ASan+UBSan, TSan, fuzzing)"
