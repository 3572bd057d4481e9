#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each for a bounded time on a
# copy of its seed corpus (tests/fuzz/corpus/NAME). A crash, leak or timeout
# fails the run and leaves the input under build-fuzz/artifacts/.
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
while read -r name binary; do
  [[ -n "$name" ]] || continue
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  if [[ -d "tests/fuzz/corpus/$name" ]]; then cp -r "tests/fuzz/corpus/$name/." "$work/"; fi
  echo "== fuzzing $name for ${seconds} s"
  "$binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="build-fuzz/artifacts/$name-" "$work" 2>&1 | tail -n 12
  rm -rf "$work"
  trap - EXIT
done < build-fuzz/fuzzers.txt
echo "== fuzzing found nothing"
