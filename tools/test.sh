#!/usr/bin/env bash
# The test command: installs what it needs, builds, checks the format, and
# runs the whole suite twice (optimised, then under AddressSanitizer + UndefinedBehaviorSanitizer,
# less the long numerical runs labelled `numeric`), the threaded tests under
# ThreadSanitizer, then the fuzzers. Prints each
# stage's time as it ends and all of them at the end, passed or not.
#   VISVOL_FUZZ_SECONDS   time per fuzz target (default here 5: the seed corpus
#                         replayed and a short run; tools/fuzz.sh alone runs 60)
#   VISVOL_FUZZ_OPT       the fuzz build's optimisation (default here -O0: half
#                         the build time, enough for a 5 s run; tools/fuzz.sh
#                         alone builds -O1)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

stage_names=()
stage_seconds=()
started=$SECONDS

report_times_of() {
  local status=$1
  echo "== stage times (2 cores: $(nproc))"
  local i
  for i in "${!stage_names[@]}"; do
    printf '   %-36s %4d s\n' "${stage_names[$i]}" "${stage_seconds[$i]}"
  done
  printf '   %-36s %4d s (%d min)\n' "total" $((SECONDS - started)) $(((SECONDS - started + 59) / 60))
  return $status
}

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
  # A tree configured with another compiler than the one asked for is built
  # again from nothing (CMake cannot change a tree's compiler in place).
  local compiler="" o
  for o in "${options[@]}"; do
    [[ $o == -DCMAKE_CXX_COMPILER=* ]] || continue
    compiler=$(command -v "${o#*=}") || {
      echo "== ${o#*=} not found (tools/deps.sh fuzz installs it)" >&2
      return 1
    }
    compiler=$(readlink -f "$compiler")
  done
  local cached=""
  [[ ! -f "$dir/CMakeCache.txt" ]] ||
    cached=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$dir/CMakeCache.txt")
  if [[ -n $compiler && -n $cached && $(readlink -f "$cached") != "$compiler" ]]; then
    echo "== $dir: configured with another compiler; building it again"
    rm -rf "$dir"
  fi
  local generator=()
  [[ -f "$dir/CMakeCache.txt" ]] || generator=(-G Ninja)
  cmake "${generator[@]}" -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVISVOL_DEBUG_INFO=-g1 \
    "${options[@]}" >/dev/null
  cmake --build "$dir" -j "$jobs" "${targets[@]}"
}


# The packages only the VM test and the fuzzers need (qemu, a kernel, clang:
# about half of what a fresh machine downloads) are installed beside the
# optimised build, which needs none of them, and waited for before any test
# runs (an install beside a test would load the machine under it). As root
# only: a password prompt cannot be answered from the background.
late_install=""
late_log=$(mktemp)
fuzz_build=""  # the fuzzers' build beside the optimised tests (its pid, its log)
fuzz_build_log=""
tsan_build=""  # the TSan tree's build beside the ASan+UBSan tests (its pid, its log)
tsan_build_log=""
wait_for_late_packages() {
  local rc=0
  if [[ -n "$late_install" ]]; then
    wait "$late_install" || rc=$?
    late_install=""
    cat "$late_log"
  fi
  ((rc == 0)) || echo "== installing the VM and fuzzer packages failed (exit $rc)" >&2
  return $rc
}
# On the way out, even after a failure: an install is never left to run unseen
# (nor stopped: dpkg must finish what it unpacks).
finish() {
  local status=$?
  if [[ -n "$late_install" ]]; then
    echo "== waiting for the package install beside the build"
    wait_for_late_packages || true
  fi
  rm -f "$late_log"
  if [[ -n "$fuzz_build" ]]; then
    echo "== waiting for the fuzzers' build beside the tests"
    wait "$fuzz_build" || true
  fi
  [[ -z "$fuzz_build_log" ]] || rm -f "$fuzz_build_log"
  if [[ -n "$tsan_build" ]]; then
    echo "== waiting for the TSan build beside the tests"
    wait "$tsan_build" || true
  fi
  [[ -z "$tsan_build_log" ]] || rm -f "$tsan_build_log"
  report_times_of "$status"
}
trap finish EXIT

# A build beside a test stage, at a low CPU priority and the idle I/O class
# (the tests keep the cores they use; the build takes what they leave idle):
# NICE 19 for the fuzzers, needed last; 10 for the TSan tree, needed before
# them, so that of the two it takes most of what the tests leave. Its output
# goes to LOG; its pid to beside_pid (a child of this shell, so that it can
# be waited for).
beside_pid=""
build_beside() {  # build_beside NICE LOG COMMAND...
  local nice=$1 log=$2
  shift 2
  (
    # best effort: a priority the shell may not take is no reason to stop
    renice -n "$nice" -p "$BASHPID" >/dev/null 2>&1 || true
    ionice -c 3 -p "$BASHPID" 2>/dev/null || true
    "$@"
  ) >"$log" 2>&1 &
  beside_pid=$!
}

# The TSan stage's build: the one begun beside the ASan+UBSan tests, its log.
tsan_build_stage() {
  local rc=0
  wait "$tsan_build" || rc=$?
  tsan_build=""
  cat "$tsan_build_log"
  return "$rc"
}

# The fuzzing stage: the build begun beside the optimised tests, then the runs.
fuzz_stage() {
  if [[ -n "$fuzz_build" ]]; then
    local rc=0
    wait "$fuzz_build" || rc=$?
    fuzz_build=""
    cat "$fuzz_build_log"
    ((rc == 0)) || return "$rc"
  fi
  tools/fuzz.sh
}

export VISVOL_FUZZ_SECONDS=${VISVOL_FUZZ_SECONDS:-5}
export VISVOL_FUZZ_OPT=${VISVOL_FUZZ_OPT:--O0}
if [[ $(id -u) -eq 0 ]]; then
  stage "install packages" tools/deps.sh build storage dds render can mpi
  tools/deps.sh vm fuzz lint >"$late_log" 2>&1 &
  late_install=$!
else
  stage "install packages" tools/deps.sh build storage dds render can mpi vm fuzz lint
fi
# The VM runs in the ASan+UBSan tree only (the same suite, the socket code
# under the sanitizers); natively, where the kernel has vcan, in both.
# visvol-build-mpi and its mpirun test: the optimised tree only (Open MPI's
# own allocations are not the project's to check under the sanitizers; the
# split build it runs is tested there through storage::build_pack_share).
stage "build: optimised" build_tree build -DVISVOL_HIL_QEMU=OFF -DVISVOL_MPI=ON
stage "install: VM + fuzz packages" wait_for_late_packages
# The fuzzers build beside the optimised tests, at the lowest CPU and I/O
# priority: those tests run console sessions and DDS exchanges in real time
# and leave about half the cores idle (their stage: 84 s of wall time, 83 s of
# CPU on 2 cores). Its log is printed in the fuzzing stage.
fuzz_build_log=$(mktemp)
build_beside 19 "$fuzz_build_log" env VISVOL_FUZZ_BUILD_ONLY=1 tools/fuzz.sh
fuzz_build=$beside_pid
stage "lint: format" tools/check_format.sh
stage "tests: optimised" ctest --test-dir build --output-on-failure -j "$jobs"
# With clang (installed with the fuzzers' packages): 211 s against GCC's
# 331 s for the same tree, its tests 145 s against 177 s (tools/bench/README.md,
# "The test command"). The optimised and TSan trees stay with GCC: both
# compilers' warnings hold.
stage "build: ASan+UBSan" build_tree build-asan -DVISVOL_SANITIZE=ON -DVISVOL_BUILD_BENCHMARKS=OFF \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
# The threaded tests' TSan tree builds beside the ASan+UBSan tests, which
# leave a fifth of the 2 cores idle (stop 42: 275 s of wall time, 441 s of
# CPU): its stage below waits for what is left of it (121 s of its 204).
tsan_build_log=$(mktemp)
build_beside 10 "$tsan_build_log" build_tree build-tsan -DVISVOL_TSAN=ON -DVISVOL_BUILD_BENCHMARKS=OFF \
  -- visvol_threaded_tests
tsan_build=$beside_pid
stage "tests: ASan+UBSan" env ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --test-dir build-asan --output-on-failure -j "$jobs" \
  -LE numeric
# The tests labelled `threaded` (ctest -L threaded; target visvol_threaded_tests):
# real threads sharing state (hand-offs, the loop, the executive, the hull
# builder, the tile pager, the DDS publisher and intake, the renderer and the
# flyable-path threads), under ThreadSanitizer.
stage "build: TSan (threaded tests; its rest)" tsan_build_stage
stage "tests: TSan" env TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp" \
  ctest --test-dir build-tsan -L threaded -LE numeric --output-on-failure -j "$jobs"
# (the build started beside the optimised tests: finished by now, or finishing)
stage "fuzzing: build and run" fuzz_stage
echo "== all tests passed (optimised, ASan+UBSan, TSan, fuzzing)"
