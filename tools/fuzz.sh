#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each for a bounded time on a
# copy of its seed corpus (tests/fuzz/corpus/NAME), one per core at a time.
# A crash, leak or timeout fails the run and leaves the input under
# build-fuzz/artifacts/.
#   VISVOL_FUZZ_SECONDS   time per target (default 60)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${VISVOL_FUZZ_SECONDS:-60}

tools/deps.sh build storage dds fuzz
generator=()
[[ -f build-fuzz/CMakeCache.txt ]] || generator=(-G Ninja)
CC=clang CXX=clang++ cmake "${generator[@]}" -S . -B build-fuzz -DVISVOL_FUZZ=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVISVOL_DEBUG_INFO=-g1 >/dev/null
cmake --build build-fuzz --target fuzzers -j "$(nproc)"

mkdir -p build-fuzz/artifacts
# fuzz_one NAME BINARY: runs one target on a copy of its corpus; its report
# goes to build-fuzz/NAME.log, printed when it ends.
fuzz_one() {
  local name=$1 binary=$2 work rc=0
  work=$(mktemp -d)
  if [[ -d "tests/fuzz/corpus/$name" ]]; then cp -r "tests/fuzz/corpus/$name/." "$work/"; fi
  "$binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="build-fuzz/artifacts/$name-" "$work" >"build-fuzz/$name.log" 2>&1 || rc=$?
  rm -rf "$work"
  echo "== fuzzed $name for ${seconds} s (exit $rc)"
  tail -n 12 "build-fuzz/$name.log"
  return "$rc"
}

# One target per core at a time; any failure fails the run once all ended.
slots=$(nproc)
failed=0
while read -r name binary; do
  [[ -n "$name" ]] || continue
  while (($(jobs -rp | wc -l) >= slots)); do wait -n || failed=1; done
  fuzz_one "$name" "$binary" &
done < build-fuzz/fuzzers.txt
while (($(jobs -rp | wc -l) > 0)); do wait -n || failed=1; done
if ((failed)); then
  echo "== fuzzing found a problem: inputs under build-fuzz/artifacts/, reports in build-fuzz/*.log" >&2
  exit 1
fi
echo "== fuzzing found nothing"
