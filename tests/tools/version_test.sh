#!/usr/bin/env bash
# version_test.sh BINARY NAME VERSION: BINARY --version prints
# "NAME VERSION (commit HASH[-dirty])" (or "commit unknown") and exits 0.
set -uo pipefail
out=$("$1" --version)
status=$?
re="^$2 ${3//./\\.} \\(commit ([0-9a-f]+(-dirty)?|unknown)\\)\$"
if ((status != 0)); then
  echo "version_test: $2 --version exited $status" >&2
  exit 1
fi
if [[ ! $out =~ $re ]]; then
  echo "version_test: $2 --version printed '$out'" >&2
  exit 1
fi
echo "$out"
