#!/usr/bin/env bash
# The include directions between the layers: a folder may not include the
# folders its rule names. Fails on any include that breaks a rule and is not
# in the list of known ones below, and on a listed one that is gone (so that
# the list only shrinks: remove its line). Run by CTest (layers_test).
#
#   rt/              the real-time core: no drivers/, no app/
#   fields/          field math: no storage/ (knows no file format), no rt/exec/, drivers/, app/
#   storage/         the pack: no drivers/, app/, rt/exec/
#   drivers/render/  thumbnails: no drivers/dds/ (messages are plain data)
set -euo pipefail
cd "$(dirname "$0")/.."

rules=(
  "rt/:drivers/|app/"
  "fields/:storage/|rt/exec/|drivers/|app/"
  "storage/:drivers/|app/|rt/exec/"
  "drivers/render/:drivers/dds/"
)

# Known breaks, FILE:INCLUDED each: the executive still takes its commands and
# device as drivers/ types, and the thumbnail its sample type from drivers/dds
# (issue 15: messages as their own layer). Nothing may be added here.
known=(
  "rt/exec/executive.cpp:drivers/dds/message_codec.hpp"
  "rt/exec/executive.hpp:drivers/can/can_bus.hpp"
  "rt/exec/executive.hpp:drivers/dds/command_processor.hpp"
  "rt/exec/executive.hpp:drivers/dds/samples.hpp"
  "rt/exec/executive.hpp:drivers/haptic/device_driver.hpp"
  "rt/exec/simulated_device.hpp:drivers/can/memory_bus.hpp"
  "rt/exec/simulated_device.hpp:drivers/hapticsim/script.hpp"
  "rt/exec/simulated_device.hpp:drivers/hapticsim/sim_device.hpp"
  "drivers/render/thumbnail.hpp:drivers/dds/samples.hpp"
)

found=()
for rule in "${rules[@]}"; do
  folder=${rule%%:*}
  forbidden=${rule#*:}
  while IFS= read -r hit; do
    [[ -n "$hit" ]] || continue
    file=${hit%%:*}
    included=$(sed -E 's/^[^:]*:#include "([^"]+)".*/\1/' <<<"$hit")
    found+=("$file:$included")
  done < <(grep -rEo "^#include \"($forbidden)[^\"]*\"" "$folder" \
             --include='*.cpp' --include='*.hpp' --include='*.h' | sort)
done

status=0
for f in "${found[@]}"; do
  if [[ " ${known[*]} " != *" $f "* ]]; then
    echo "layers: ${f%%:*} includes ${f#*:}, which its folder's rule forbids" >&2
    status=1
  fi
done
for k in "${known[@]}"; do
  if [[ " ${found[*]} " != *" $k "* ]]; then
    echo "layers: ${k%%:*} no longer includes ${k#*:}: remove that line from the known breaks in $0" >&2
    status=1
  fi
done
if ((status == 0)); then
  echo "layers: ${#rules[@]} rules hold (${#known[@]} known breaks listed)"
fi
exit "$status"
