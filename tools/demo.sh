#!/usr/bin/env bash
# The main job on the bundled default: builds the visibility field of the San
# Francisco North DEM (three levels of detail), prints its summary and writes
# the outputs to out/ (or $VISVOL_OUT).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${VISVOL_OUT:-out}

tools/deps.sh build
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j "$(nproc)" --target visvol

mkdir -p "$out"
dem=tests/data/sf_north_utm10_30m.tif
visvol=build/tools/visvol/visvol

echo "== visibility field of $dem"
"$visvol" build "$dem" --fill-nodata --lod 3 --json-file "$out/field_summary.json" \
  | tee "$out/field_summary.txt"

echo "== viewshed of an observer 2 m above the highest post"
"$visvol" viewshed "$dem" --fill-nodata --observer 544200 4189200 --observer-height 2 \
  -o "$out/viewshed_highest_post.tif" | tee "$out/viewshed.txt"

echo
echo "outputs in $out/:"
ls -1 "$out" | sed 's/^/  /'
