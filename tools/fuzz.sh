#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each for a bounded time on a
# copy of its seed corpus (tests/fuzz/corpus/NAME), one per core at a time.
# A crash, leak or timeout fails the run and leaves the input under
# build-fuzz/artifacts/.
#   VISVOL_FUZZ_SECONDS   time per target (default 60)
#   VISVOL_FUZZ_OPT       the fuzz build's optimisation (default -O1; the test
#                         command's short run takes -O0: faster to build)
#   VISVOL_FUZZ_BUILD_ONLY 1: build the targets, run none
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${VISVOL_FUZZ_SECONDS:-60}

tools/deps.sh build storage dds fuzz
generator=()
[[ -f build-fuzz/CMakeCache.txt ]] || generator=(-G Ninja)
CC=clang CXX=clang++ cmake "${generator[@]}" -S . -B build-fuzz -DVISVOL_FUZZ=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVISVOL_DEBUG_INFO=-g1 -DVISVOL_FUZZ_OPT="${VISVOL_FUZZ_OPT:--O1}" >/dev/null
cmake --build build-fuzz --target fuzzers -j "$(nproc)"
# VISVOL_FUZZ_BUILD_ONLY=1: the build alone (the test command builds the
# fuzzers while its optimised tests leave the cores half idle)
[[ "${VISVOL_FUZZ_BUILD_ONLY:-0}" == 1 ]] && exit 0

mkdir -p build-fuzz/artifacts
scratch=$(mktemp -d)
# on the way out (an interrupt, a failure) the fuzzers still running are
# stopped (they are the children of the fuzz_one jobs), then their corpora removed
stop_fuzzers() {
  local job
  for job in $(jobs -p); do
    pkill -TERM -P "$job" 2>/dev/null || true
    kill "$job" 2>/dev/null || true
  done
  wait 2>/dev/null || true
  rm -rf "$scratch"
}
trap stop_fuzzers EXIT

# fuzz_one NAME BINARY: runs one target on a copy of its corpus; its report
# goes to build-fuzz/NAME.log (printed when it ends), its exit status to
# $scratch/NAME.rc.
fuzz_one() {
  local name=$1 binary=$2 rc=0
  mkdir -p "$scratch/$name"
  if [[ -d "tests/fuzz/corpus/$name" ]]; then cp -r "tests/fuzz/corpus/$name/." "$scratch/$name/"; fi
  "$binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="build-fuzz/artifacts/$name-" "$scratch/$name" >"build-fuzz/$name.log" 2>&1 || rc=$?
  echo "$rc" >"$scratch/$name.rc"
  echo "== fuzzed $name for ${seconds} s (exit $rc)"
  tail -n 12 "build-fuzz/$name.log"
}

# One target per core at a time; the run fails when any target failed.
slots=$(nproc)
names=()
while read -r name binary; do
  [[ -n "$name" ]] || continue
  while (($(jobs -rp | wc -l) >= slots)); do wait -n || true; done
  fuzz_one "$name" "$binary" &
  names+=("$name")
done < build-fuzz/fuzzers.txt
wait
failed=()
for name in "${names[@]}"; do
  [[ "$(cat "$scratch/$name.rc" 2>/dev/null || echo missing)" == 0 ]] || failed+=("$name")
done
if ((${#failed[@]})); then
  echo "== fuzzing found a problem in: ${failed[*]} (inputs under build-fuzz/artifacts/, reports in build-fuzz/NAME.log)" >&2
  exit 1
fi
echo "== fuzzing found nothing (${#names[@]} targets)"
