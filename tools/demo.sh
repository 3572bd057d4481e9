#!/usr/bin/env bash
# The main job on the bundled default: imports the San Francisco North DEM,
# builds its field pack (visibility field F_p with three levels of detail and
# the terrain force field), checks it, samples it, exports it, writes a
# viewshed, plans a hidden path offline and draws it, then runs the console
# for 24 s: the 1 kHz executive with the simulated haptic device (the built-in
# operator script grabs and pulls the rope in pull mode, then switches to spool
# mode and drags a rope out from the start to the far end), DDS on loopback,
# thumbnails, and a hidden-from constraint sent to it over DDS by visvol-echo.
# Outputs go to out/ (or $VISVOL_OUT).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${VISVOL_OUT:-out}

tools/deps.sh build storage dds render
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j "$(nproc)" --target visvol visvol-console visvol-echo

mkdir -p "$out"
dem=tests/data/sf_north_utm10_30m.tif
pack=$out/sf_north.vvp
visvol=build/tools/visvol/visvol

echo "== field pack of $dem"
"$visvol" build "$dem" --fill-nodata -o "$pack" | tee "$out/build.txt"

echo "== what the pack holds"
"$visvol" info "$pack" | tee "$out/info.txt"
"$visvol" info "$pack" --json > "$out/info.json"
"$visvol" verify "$pack"

echo "== F_p above the Presidio, the city and the Golden Gate (x y z in UTM 10N metres)"
printf '%s\n' "545500 4185500 150" "550500 4183000 150" "546000 4189500 150" "546000 4189500 600" \
  | tee "$out/points.txt" \
  | "$visvol" sample "$pack" --layer visibility | tee "$out/samples.txt"

echo "== export for ParaView / 3D Slicer / VolView"
"$visvol" export "$pack" --layer visibility --lod 1 --format vti -o "$out/visibility_lod1.vti"

echo "== viewshed of an observer 2 m above the highest post"
"$visvol" viewshed "$dem" --fill-nodata --observer 544200 4189200 --observer-height 2 \
  -o "$out/viewshed_highest_post.tif" | tee "$out/viewshed.txt"

echo "== a path hidden from the ground, Marin Headlands to downtown (global search, then the rope),"
echo "   flown by the default fixed-wing vehicle and checked by exact sight lines on the finest terrain"
# exit 1 means a requirement is unmet: the path is still written, and the summary says which
"$visvol" plan "$pack" --from 546000 4189000 200 --to 553000 4182000 200 --objective hide \
  --init global --segments 128 -o "$out/plan_hide" | tee "$out/plan_hide.txt" ||
  echo "visvol plan: a requirement is unmet (see $out/plan_hide.txt)"

echo "== the written QGroundControl mission, assessed on its own"
"$visvol" check "$pack" "$out/plan_hide.plan" --json >"$out/plan_hide_check.json" ||
  echo "visvol check: a requirement is unmet (see $out/plan_hide_check.json)"

echo "== thumbnails of the plan"
for view in oblique volume slice; do
  "$visvol" render "$pack" --path "$out/plan_hide.csv" --view "$view" --size 640x480 \
    -o "$out/plan_hide_$view.png"
done

echo "== the console: 24 s at 1 kHz, simulated haptic device, DDS on loopback (domain 0);"
echo "   at 8 s a second station tells it over DDS to stay hidden from an observer on the ground"
echo "   south of the Presidio (a corridor hidden from it exists: visvol plan finds one);"
echo "   pull mode (A) until 15 s, then spool mode (B): a rope paid out from the start as the"
echo "   operator drags its free end to the far end (summary.json: mode, spool.paid_out_m)"
(
  sleep 8
  build/tools/echo/visvol-echo command --wait-applied set-constraints --hidden-from 547250,4182750,109 --clearance 30 \
    >"$out/console_command.txt" 2>&1 || echo "visvol-echo failed: see $out/console_command.txt"
) &
build/app/visvol-console --pack "$pack" --seconds 24 --out "$out/console"
wait

echo
echo "outputs in $out/:"
ls -1 "$out" | sed 's/^/  /'
