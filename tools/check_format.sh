#!/usr/bin/env bash
# The C++ sources as .clang-format formats them (clang-format 14, Debian's).
#   tools/check_format.sh         lists the files that differ; exit 1 if any
#   tools/check_format.sh --fix   formats them in place
# The test command runs the check (stage "lint: format"); deps.sh lint installs
# clang-format.
set -euo pipefail
cd "$(dirname "$0")/.."

format=$(command -v clang-format-14 || command -v clang-format || true)
if [[ -z "$format" ]]; then
  echo "check_format: clang-format not found (tools/deps.sh lint installs it)" >&2
  exit 2
fi
mapfile -t files < <(git ls-files -- '*.cpp' '*.hpp' '*.h' 2>/dev/null)
if ((${#files[@]} == 0)); then  # clang-format would read standard input
  echo "check_format: no C++ files listed by git (run it in a git checkout)" >&2
  exit 2
fi
if [[ "${1:-}" == "--fix" ]]; then
  "$format" -i "${files[@]}"
  exit 0
elif [[ $# -gt 0 ]]; then
  echo "usage: tools/check_format.sh [--fix]" >&2
  exit 2
fi
# One run over every file; each difference is reported as FILE:LINE:COL: error.
rc=0
out=$("$format" --dry-run -Werror "${files[@]}" 2>&1) || rc=$?
mapfile -t bad < <(sed -nE 's/^([^:]+):[0-9]+:[0-9]+: error: .*/\1/p' <<<"$out" | sort -u)
if ((${#bad[@]} > 0)); then
  echo "check_format: ${#bad[@]} of ${#files[@]} files are not formatted (tools/check_format.sh --fix):" >&2
  printf '  %s\n' "${bad[@]}" >&2
  exit 1
elif ((rc != 0)); then
  printf '%s\n' "$out" >&2
  echo "check_format: clang-format failed (exit $rc)" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files formatted ($("$format" --version | head -1))"
