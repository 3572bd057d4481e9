#!/usr/bin/env bash
# The include directions between the layers. Every folder of C++ sources has a
# rule: the project folders it may include (an allow-list, so a new folder or a
# new dependency fails until a rule says it may be). The longest matching
# prefix of a file's path picks its rule. Run by CTest (layers_test).
#
#   base/            the error type and the lock-free hand-off: real-time safe, no other layer
#   io/              blocking file input and output (start-up and offline code only)
#   msg/             the messages: plain data, no transport
#   fields/          field math: no file format, no pack (fields/gdal/ imports DEMs)
#   storage/         the pack: format, reader, writer, builder
#   rt/              the real-time core: no io/, no drivers/, no app/, no transport
#   drivers/         devices and transports; drivers/render/ has no DDS
#   app/, tools/     wire everything; tools/bench/ may use tests/support/
#   tests/           anything
# Quoted and angle-bracket includes both count, however spaced; a path that
# climbs (`..`) or starts at `./` is refused outside tests/ (it would dodge the
# rules). Cyclone DDS's headers and the ones idlc generates (the transport) are
# allowed in drivers/dds/ and tests/ only. VISVOL_LAYERS_ROOT checks another
# tree (tests/tools/check_layers_test.sh plants breaks in one).
set -euo pipefail
cd "${VISVOL_LAYERS_ROOT:-$(dirname "$0")/..}"

# The project's top-level folders: an include that starts with one of them is
# the project's own (anything else is a system or library header).
project='base|io|msg|rt|fields|storage|drivers|app|tools|tests'
cyclone='dds/|ddsc/|ros2\.h|visvol_msgs\.h'

# FOLDER:ALLOWED, ALLOWED a regular expression over included paths.
rules=(
  "base/:base/"
  "io/:base/|io/"
  "msg/:base/|msg/"
  "fields/gdal/:base/|io/|fields/"
  "fields/:base/|fields/[a-z0-9_]+\.hpp$"
  "storage/:base/|io/|fields/|storage/"
  "rt/servo/:base/|rt/servo/"
  "rt/rope/:base/|fields/[a-z0-9_]+\.hpp$|rt/rope/"
  "rt/exec/:base/|msg/|fields/[a-z0-9_]+\.hpp$|storage/resident_pack\.hpp$|rt/"
  "drivers/can/:base/|io/|drivers/can/"
  "drivers/haptic/:base/|io/|rt/exec/haptic_device\.hpp|drivers/can/|drivers/haptic/"
  "drivers/hapticsim/:base/|io/|rt/exec/haptic_device\.hpp|drivers/can/|drivers/haptic/|drivers/hapticsim/"
  "drivers/dds/:base/|io/|msg/|drivers/dds/|$cyclone"
  "drivers/render/:base/|io/|msg/|fields/|storage/|drivers/render/"
  "app/:base/|io/|msg/|fields/|storage/|rt/|drivers/|app/"
  "tools/bench/:base/|io/|msg/|fields/|storage/|rt/|drivers/|tools/|tests/support/"
  "tools/:base/|io/|msg/|fields/|storage/|rt/|drivers/|app/|tools/"
  "tests/:.*"
)

rule_for() {  # the allowed pattern of the longest folder that prefixes $1
  local best='' allowed='' r folder
  for r in "${rules[@]}"; do
    folder=${r%%:*}
    if [[ $1 == "$folder"* && ${#folder} -gt ${#best} ]]; then
      best=$folder
      allowed=${r#*:}
    fi
  done
  [[ -n $best ]] && printf '%s' "$allowed"
}

sources() {  # the C++ files of a checkout (tracked or new, not ignored), or of an export
  local globs=('*.cpp' '*.hpp' '*.h' '*.cc' '*.c' '*.inl' '*.ipp')
  if [[ $(git rev-parse --show-toplevel 2>/dev/null) == "$(pwd -P)" ]]; then
    git ls-files -co --exclude-standard -- "${globs[@]}"
  else
    find . -mindepth 1 \( -path './build*' -o -name '.*' \) -prune -o -type f \( -name '*.cpp' -o -name '*.hpp' \
      -o -name '*.h' -o -name '*.cc' -o -name '*.c' -o -name '*.inl' -o -name '*.ipp' \) -print | sed 's|^\./||' | sort
  fi
}

status=0
checked=0
while IFS= read -r file; do
  if ! allowed=$(rule_for "$file"); then
    echo "layers: $file lies in a folder no rule names: add its rule to $0" >&2
    status=1
    continue
  fi
  checked=$((checked + 1))
  while IFS= read -r included; do
    [[ -n $included ]] || continue
    if [[ $file != tests/* && ($included == *..* || $included == ./*) ]]; then
      echo "layers: $file includes $included: a relative path dodges the layer rules (name it from the root)" >&2
      status=1
    elif [[ $included =~ ^(($project)/|$cyclone) && ! $included =~ ^($allowed) ]]; then
      echo "layers: $file includes $included, which its folder's rule does not allow" >&2
      status=1
    fi
  done < <(sed -nE 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]([^">]+)[">].*/\1/p' "$file")
done < <(sources)

if ((checked == 0)); then
  echo "layers: no C++ file found under $(pwd): nothing checked" >&2
  status=1
fi
if ((status == 0)); then
  echo "layers: ${#rules[@]} rules hold over $checked files"
fi
exit "$status"
