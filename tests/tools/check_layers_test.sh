#!/usr/bin/env bash
# tools/check_layers.sh checked on trees with planted breaks: each break is
# named, a clean tree passes, an empty one fails. Run by CTest (layers_checker_test).
set -euo pipefail
checker="$(cd "$(dirname "$0")/../.." && pwd)/tools/check_layers.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

plant() {  # plant FILE LINE...
  mkdir -p "$tmp/$(dirname "$1")"
  local f=$1
  shift
  printf '%s\n' "$@" >"$tmp/$f"
}
run() {  # run: the checker on $tmp; sets rc and out
  rc=0
  out=$(VISVOL_LAYERS_ROOT="$tmp" bash "$checker" 2>&1) || rc=$?
}
fail() {
  echo "check_layers_test: $*" >&2
  echo "$out" >&2
  exit 1
}

# allowed: a clean tree
plant base/status.hpp '#pragma once'
plant io/atomic_file.hpp '#include "base/status.hpp"'
plant rt/rope/rope.hpp '#include "base/status.hpp"' '#include "fields/volume.hpp"' '#include <vector>'
plant fields/volume.hpp '#include "base/status.hpp"'
plant tests/rt/rope_test.cpp '#include "../fields/terrains.hpp"' '#include "io/atomic_file.hpp"' '#include <dds/dds.h>'
run
[[ $rc == 0 ]] || fail "a clean tree failed"

# each break, however written, is named
plant rt/rope/bad1.hpp '#include "io/atomic_file.hpp"'
plant msg/bad2.hpp '#include <dds/dds.h>'
plant fields/bad3.hpp '#  include   "fields/gdal/dem_io.hpp"'
plant rt/exec/bad4.cpp '  #include "storage/pack_writer.hpp"'
plant app/bad5.cpp '#include "../rt/rope/rope.hpp"'
plant newlayer/bad6.hpp '#include "base/status.hpp"'
plant drivers/render/bad7.inl '#include "drivers/dds/topics.hpp"'
run
[[ $rc == 1 ]] || fail "planted breaks passed (status $rc)"
for expect in 'rt/rope/bad1.hpp includes io/atomic_file.hpp' 'msg/bad2.hpp includes dds/dds.h' \
  'fields/bad3.hpp includes fields/gdal/dem_io.hpp' 'rt/exec/bad4.cpp includes storage/pack_writer.hpp' \
  'app/bad5.cpp includes ../rt/rope/rope.hpp' 'newlayer/bad6.hpp lies in a folder no rule names' \
  'drivers/render/bad7.inl includes drivers/dds/topics.hpp'; do
  [[ $out == *"$expect"* ]] || fail "not named: $expect"
done
[[ $out != *rope_test* && $out != *rope.hpp\ includes* ]] || fail "an allowed include was named"

# nothing to check is a failure, not a pass
rm -rf "${tmp:?}"/*
run
[[ $rc == 1 && $out == *"no C++ file found"* ]] || fail "an empty tree passed"
echo "check_layers_test: 7 planted breaks named, a clean tree passes, an empty one fails"
