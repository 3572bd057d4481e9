#!/usr/bin/env bash
# The include directions between the layers: a folder may not include the
# folders its rule names. Fails on any include that breaks a rule and is not
# in the list of known ones below, and on a listed one that is gone (so that
# the list only shrinks: remove its line). Run by CTest (layers_test).
#
#   rt/base/         the base: no other layer (msg/ builds on it)
#   rt/              the real-time core: no drivers/, no app/, no DDS
#   fields/          field math: no storage/ (knows no file format), no rt/exec/, drivers/, app/
#   storage/         the pack: no drivers/, app/, rt/exec/
#   msg/             the messages: plain data on rt/base/, no transport, no other layer
#   drivers/render/  thumbnails: no drivers/dds/, no DDS (messages are plain data)
# Includes in quotes and in angle brackets both count.
set -euo pipefail
cd "$(dirname "$0")/.."

# Cyclone DDS's own headers and the ones idlc generates: the transport.
cyclone='dds/|ddsc/|ros2\.h|visvol_msgs\.h'
rules=(
  "rt/base/:msg/|rt/exec/|rt/rope/|rt/servo/|fields/|storage/|$cyclone"
  "rt/:drivers/|app/|$cyclone"
  "msg/:drivers/|app/|rt/exec/|rt/rope/|rt/servo/|fields/|storage/|tools/|$cyclone"
  "fields/:storage/|rt/exec/|drivers/|app/"
  "storage/:drivers/|app/|rt/exec/"
  "drivers/render/:drivers/dds/|$cyclone"
)

# Known breaks, FILE:INCLUDED each. None today; nothing may be added here (a
# new break is fixed, not listed).
known=()

found=()
for rule in "${rules[@]}"; do
  folder=${rule%%:*}
  forbidden=${rule#*:}
  while IFS= read -r hit; do
    [[ -n "$hit" ]] || continue
    file=${hit%%:*}
    included=$(sed -E 's/^[^:]*:#include [<"]([^">]+)[">].*/\1/' <<<"$hit")
    found+=("$file:$included")
  done < <(grep -rEo "^#include [<\"]($forbidden)[^\">]*[\">]" "$folder" \
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
