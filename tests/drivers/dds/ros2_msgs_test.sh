#!/usr/bin/env bash
# ros2_msgs_test.sh SOURCE_DIR: the ROS 2 package drivers/dds/ros2/visvol_msgs
# carries the IDL's messages: its msg/ files are what
# tools/ros2/gen_visvol_msgs.py makes of drivers/dds/idl/visvol_msgs.idl
# today (same fields, same order, same constants), its CMakeLists.txt lists
# each of them, and the generator refuses an IDL type it has no ROS 2 type for.
set -euo pipefail
src=$1
gen=$src/tools/ros2/gen_visvol_msgs.py
pkg=$src/drivers/dds/ros2/visvol_msgs
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

python3 "$gen" "$src/drivers/dds/idl/visvol_msgs.idl" "$scratch/msg"
if ! diff -ru "$scratch/msg" "$pkg/msg"; then
  echo "ros2_msgs_test: $pkg/msg is not the IDL's: run tools/ros2/gen_visvol_msgs.py" \
    "drivers/dds/idl/visvol_msgs.idl drivers/dds/ros2/visvol_msgs/msg" >&2
  exit 1
fi

structs=$(grep -oE '@final struct [A-Z][A-Za-z0-9]*_' "$src/drivers/dds/idl/visvol_msgs.idl" | sed 's/.* //; s/_$//' | sort)
files=$(cd "$pkg/msg" && ls -- *.msg | sed 's/\.msg$//' | sort)
listed=$(grep -oE '"msg/[A-Za-z0-9]+\.msg"' "$pkg/CMakeLists.txt" | sed 's|"msg/||; s|\.msg"||' | sort)
[[ $structs == "$files" ]] || { echo "ros2_msgs_test: IDL structs ($structs) and msg files ($files) differ" >&2; exit 1; }
[[ $files == "$listed" ]] || { echo "ros2_msgs_test: CMakeLists.txt lists ($listed), msg/ has ($files)" >&2; exit 1; }
grep -q '<name>visvol_msgs</name>' "$pkg/package.xml" || { echo "ros2_msgs_test: package.xml names another package" >&2; exit 1; }

# an IDL type without a ROS 2 counterpart is refused, naming the line
printf 'module visvol_msgs { module msg { module dds_ {\n  @final struct Odd_ {\n    float ratio;\n  };\n}; }; };\n' \
  >"$scratch/odd.idl"
if python3 "$gen" "$scratch/odd.idl" "$scratch/odd" 2>"$scratch/err"; then
  echo "ros2_msgs_test: the generator took a float" >&2
  exit 1
fi
grep -q "line 3: no ROS 2 type for 'float'" "$scratch/err" || { cat "$scratch/err" >&2; exit 1; }
echo "ros2_msgs_test: $(echo "$files" | wc -w) messages match the IDL"
