#!/usr/bin/env bash
# clang-tidy with the project's .clang-tidy over every translation unit of the
# project's libraries and programs (tests and benchmarks excluded) in a build
# tree's compile_commands.json. Fails on any finding (the checks listed are the ones
# the code honours; a finding is fixed, or NOLINT(check) with a reason).
#
#   tools/check_tidy.sh [BUILD_DIR] [JOBS]     (default: build, all cores)
#
# The tree must be configured without precompiled headers (clang cannot read
# GCC's): cmake -S . -B build-tidy -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON
#
# Not a stage of tools/test.sh: it parses every file again with clang, about
# half a minute of CPU a file (about 40 minutes on 2 cores). The `visvol`
# command's sources are compiled as unity files, which this leaves out.
# Needs Debian's clang-tidy (tools/deps.sh tidy).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
jobs=${2:-$(nproc)}
tools/deps.sh tidy
if [[ ! -f $build/compile_commands.json ]]; then
  echo "check_tidy: $build/compile_commands.json not found: configure that tree first" >&2
  exit 2
fi
if grep -q cmake_pch "$build/compile_commands.json"; then
  echo "check_tidy: $build uses GCC's precompiled headers, which clang cannot read:" \
    "configure a tree with -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON" >&2
  exit 2
fi
# the project's own sources: not the tests, not generated or unity files
root=$(pwd | sed 's/[][\\.^$*+?(){}|]/\\&/g')  # the path, regex-escaped
files="^$root/(base|io|msg|rt|fields|storage|drivers|app|tools/(visvol|echo|hapticsim))/.*\\.cpp\$"
run-clang-tidy -quiet -p "$build" -j "$jobs" "$files"
