#!/usr/bin/env bash
# Installs the Debian packages a visvol command needs: only the missing ones,
# quietly, and nothing at all when everything is present.
#   tools/deps.sh SET...   with SET one of: build storage dds render hil (= can vm) can vm fuzz lint tidy rt mpi all
set -euo pipefail

build_packages=(
  cmake g++ make ninja-build pkg-config
  lld                    # the linker (CMakeLists.txt: VISVOL_LINKER), a fifth of GNU ld's time on the tests
  libeigen3-dev          # vectors and matrices (rope, sampler, servo)
  libgdal-dev            # DEM import and GeoTIFF output (offline tools only)
  libproj-dev proj-data  # path files: DEM (EGM96) heights to WGS84 ellipsoidal ones for GeoJSON (the EGM96 grid)
  libcli11-dev           # command-line parsing
  nlohmann-json3-dev     # --json output
  libgtest-dev libgmock-dev  # unit tests
  libbenchmark-dev       # micro-benchmarks
  libtomlplusplus-dev    # vehicle files (visvol plan --vehicle FILE)
  libsystemd-dev         # sd_notify: the console as a systemd unit (READY, WATCHDOG, STOPPING)
  python3                # tools/ros2/gen_visvol_msgs.py: the ROS 2 messages from the IDL (and its test)
  dpkg-dev file          # cpack -G DEB: dpkg-shlibdeps for the package's Depends, file to find the ELF programs
)

storage_packages=(libisal-dev libssl-dev)           # CRC32C of pack tiles, SHA-256 of sources
dds_packages=(cyclonedds-dev cyclonedds-tools)      # DDS participants, idlc
render_packages=(libosmesa6-dev libpng-dev)         # offscreen GL, PNG thumbnails
can_packages=(can-utils)                            # candump (the vcan suite, native or in the VM)
vm_packages=(qemu-system-x86 linux-image-amd64 busybox-static cpio)  # vcan in a VM
fuzz_packages=(clang libclang-rt-14-dev)            # libFuzzer targets; the ASan+UBSan test tree
lint_packages=(clang-format)                        # the format check (tools/check_format.sh)
tidy_packages=(clang-tidy)                          # tools/check_tidy.sh (not a test stage)
rt_packages=(rt-tests)                              # cyclictest, beside the executive benchmark
mpi_packages=(openmpi-bin libopenmpi-dev)           # visvol-build-mpi: mpirun, MPI and MPI-IO

wanted=()
for set in "${@:-build}"; do
  case "$set" in
    build) wanted+=("${build_packages[@]}") ;;
    storage) wanted+=("${storage_packages[@]}") ;;
    dds) wanted+=("${dds_packages[@]}") ;;
    render) wanted+=("${render_packages[@]}") ;;
    hil) wanted+=("${can_packages[@]}" "${vm_packages[@]}") ;;
    can) wanted+=("${can_packages[@]}") ;;
    vm) wanted+=("${vm_packages[@]}") ;;
    fuzz) wanted+=("${fuzz_packages[@]}") ;;
    lint) wanted+=("${lint_packages[@]}") ;;
    tidy) wanted+=("${tidy_packages[@]}") ;;
    rt) wanted+=("${rt_packages[@]}") ;;
    mpi) wanted+=("${mpi_packages[@]}") ;;
    all) wanted+=("${build_packages[@]}" "${storage_packages[@]}" "${dds_packages[@]}"
                  "${render_packages[@]}" "${can_packages[@]}" "${vm_packages[@]}" "${fuzz_packages[@]}"
                  "${lint_packages[@]}" "${tidy_packages[@]}" "${rt_packages[@]}" "${mpi_packages[@]}") ;;
    *) echo "tools/deps.sh: unknown package set '$set'" \
            "(known: build storage dds render hil can vm fuzz lint tidy rt mpi all)" >&2
       exit 2 ;;
  esac
done

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
