#!/usr/bin/env bash
# console_config_example_test.sh CONSOLE EXAMPLE: the example configuration
# (app/systemd/console.toml, the package's /etc/visvol/console.toml) and the
# console's options cannot drift apart:
#   - its keys (each "#key = value" or "key = value" line) are exactly the long
#     options `CONSOLE --help` lists, less --help, --version and --config, each once;
#   - every other line is blank, a comment ("# ...") or a [section];
#   - CONSOLE --config EXAMPLE is accepted as is, and with every key
#     uncommented (the values written must be valid, each key in its own
#     section): with a file that is not a pack as --pack, start-up gets past
#     the options and refuses that file.
set -euo pipefail
console=$1 example=$2
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
failures=0
fail() {
  echo "console_config_example_test: $*" >&2
  failures=$((failures + 1))
}

# The long options of --help: the first column of each option line
# ("  --name ..." or "  -o,--name ..."); descriptions that name options do
# not count.
"$console" --help >"$scratch/help"
sed -nE 's/^  (-[A-Za-z],)?--([a-z0-9][a-z0-9-]*).*/\2/p' "$scratch/help" |
  grep -vxE 'help|version|config' | sort >"$scratch/options"
(($(wc -l <"$scratch/options") > 0)) || fail "no options found in $console --help"

sed -nE 's/^#?([a-z0-9][a-z0-9-]*) = .*/\1/p' "$example" | sort >"$scratch/keys"
if dups=$(uniq -d "$scratch/keys") && [[ -n $dups ]]; then
  fail "keys given more than once in $example: $dups"
fi
if missing=$(comm -23 "$scratch/options" <(sort -u "$scratch/keys")) && [[ -n $missing ]]; then
  fail "options of --help missing from $example: $(tr '\n' ' ' <<<"$missing")"
fi
if extra=$(comm -13 "$scratch/options" <(sort -u "$scratch/keys")) && [[ -n $extra ]]; then
  fail "keys of $example that --help does not list: $(tr '\n' ' ' <<<"$extra")"
fi
if stray=$(grep -nvE '^$|^# |^#$|^#?[a-z0-9][a-z0-9-]* = |^\[[a-z]+\]$' "$example") && [[ -n $stray ]]; then
  fail "lines of $example that are neither a comment (\"# ...\"), a key nor a [section]:"$'\n'"$stray"
fi
if set_keys=$(grep -nE '^[a-z]' "$example") && [[ -n $set_keys ]]; then
  fail "keys of $example set rather than commented out at their defaults:"$'\n'"$set_keys"
fi

# Accepted: parsed and validated, then the pack refused (not a pack).
not_pack=$scratch/not_a_pack.vvp
printf 'not a pack\n' >"$not_pack"
accepted() {  # accepted NAME CONFIG: the console gets past its options
  local status=0
  "$console" --config "$2" --pack "$not_pack" >"$scratch/out" 2>"$scratch/err" || status=$?
  if ((status != 2)) || ! grep -qF "$not_pack: " "$scratch/err"; then
    fail "$1: exit $status (2 and a refusal of $not_pack expected): $(cat "$scratch/err")"
  fi
}
accepted "the example as is" "$example"
# every key set; the files and folders it names replaced by existing ones
sed -E 's/^#([a-z])/\1/' "$example" |
  sed -E "s|^(pack\|terrain\|dds-config) = .*|\1 = \"$not_pack\"|; s|^catalogue = .*|catalogue = \"$scratch\"|" \
    >"$scratch/all.toml"
accepted "the example with every key set" "$scratch/all.toml"

if ((failures > 0)); then
  echo "console_config_example_test: $failures failures" >&2
  exit 1
fi
echo "console_config_example_test: $(wc -l <"$scratch/options") options, as $example names them"
