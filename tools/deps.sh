#!/usr/bin/env bash
# Installs the Debian packages a visvol command needs: only the missing ones,
# quietly, and nothing at all when everything is present.
#   tools/deps.sh build   compilers, libraries and test frameworks
set -euo pipefail

build_packages=(
  cmake g++ make pkg-config
  libeigen3-dev          # vectors and matrices (rope, sampler, servo)
  libgdal-dev            # DEM import and GeoTIFF output (offline tools only)
  libcli11-dev           # command-line parsing
  nlohmann-json3-dev     # --json output
  libgtest-dev libgmock-dev  # unit tests
  libbenchmark-dev       # micro-benchmarks
)

case "${1:-build}" in
  build) wanted=("${build_packages[@]}") ;;
  *) echo "tools/deps.sh: unknown package set '$1' (known: build)" >&2; exit 2 ;;
esac

missing=()
for p in "${wanted[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
((${#missing[@]} == 0)) && exit 0

sudo=""
[[ $(id -u) -eq 0 ]] || sudo="sudo"
echo "installing Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
