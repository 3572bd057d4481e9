#!/usr/bin/env bash
# Runs the vcan hardware-in-the-loop suite (hil_vcan_test) inside a throw-away
# VM: Debian's own kernel under qemu-system-x86_64 -accel tcg (KVM hangs on the
# CI machines), a busybox initramfs holding the suite, visvol-hapticsim,
# candump, the shared libraries any of them needs (the ASan+UBSan tree cannot
# link statically) and the CAN modules; vcan0 inside. The guest prints the
# suite's output and "EXIT=<status>" on its serial console.
#
#   run_qemu.sh WORKDIR TEST_BINARY SIMULATOR
#
# Exit status: the suite's; 77 (CTest: skipped), with the reason, where the
# host kernel has vcan (the suite then runs natively as hil_vcan_test) or a
# package is missing (tools/deps.sh hil installs them).
# Environment: VISVOL_HIL_QEMU_TIMEOUT (s, default 160); VISVOL_HIL_SLACK_MS
# and VISVOL_HIL_TIMEOUT_MS (40 and 60: timing tolerance and timeouts inside the
# emulated guest, whose scheduling stalls for tens of ms: the guest checks
# behaviour, the host checks the 10 ms timing); ASAN_OPTIONS,
# UBSAN_OPTIONS and GTEST_FILTER are passed into the guest.
set -euo pipefail

workdir=$1
test_bin=$2
sim_bin=$3
timeout_s=${VISVOL_HIL_QEMU_TIMEOUT:-160}
slack_ms=${VISVOL_HIL_SLACK_MS:-40}
timeout_ms=${VISVOL_HIL_TIMEOUT_MS:-60}

skip() {
  echo "hil_vcan_qemu skipped: $*"
  exit 77
}

# Natively where the kernel can (hil_vcan_test runs the same suite there).
if probe=$("$test_bin" --probe 2>&1); then
  skip "$probe: the suite runs natively as hil_vcan_test"
fi
for tool in qemu-system-x86_64 cpio gzip candump; do
  command -v "$tool" >/dev/null || skip "$tool not found (tools/deps.sh hil installs it)"
done
busybox=/bin/busybox
[[ -x $busybox ]] || skip "$busybox not found (install busybox-static)"
if ldd "$busybox" >/dev/null 2>&1; then skip "$busybox is not static (install busybox-static)"; fi

# The newest installed Debian kernel that has the vcan module; never a fixed version.
kernel="" version="" moddir=""
for k in $(ls -1 /boot/vmlinuz-* 2>/dev/null | sort -V -r); do
  v=${k#/boot/vmlinuz-}
  if [[ -r $k ]] && compgen -G "/lib/modules/$v/kernel/drivers/net/can/vcan.ko*" >/dev/null; then
    kernel=$k version=$v moddir=/lib/modules/$v/kernel
    break
  fi
done
[[ -n $kernel ]] || skip "no readable /boot/vmlinuz-* with CAN modules (tools/deps.sh hil installs linux-image-amd64)"

# The initramfs.
root=$workdir/root
rm -rf "$workdir"
mkdir -p "$root"/{bin,hil,mod,proc,sys,dev,tmp}
cp "$busybox" "$root/bin/busybox"

copy_module() {  # copy_module PATH_WITHOUT_SUFFIX NAME: .ko, .ko.xz or .ko.zst
  local base=$1 name=$2
  if [[ -f $base.ko ]]; then cp "$base.ko" "$root/mod/$name.ko"
  elif [[ -f $base.ko.xz ]]; then xz -dc "$base.ko.xz" >"$root/mod/$name.ko"
  elif [[ -f $base.ko.zst ]]; then zstd -qdc "$base.ko.zst" >"$root/mod/$name.ko"
  else
    echo "hil_vcan_qemu: module $base.ko not found in $moddir" >&2
    exit 1
  fi
}
# Load order matters: without can-dev, vcan fails with "Unknown symbol can_dropped_invalid_skb".
copy_module "$moddir/net/can/can" can
copy_module "$moddir/net/can/can-raw" can-raw
copy_module "$moddir/drivers/net/can/dev/can-dev" can-dev
copy_module "$moddir/drivers/net/can/vcan" vcan

copy_binary() {  # copy_binary PATH NAME: without debug info, plus its shared libraries
  local bin=$1 name=$2
  strip --strip-debug -o "$root/hil/$name" "$bin" 2>/dev/null || cp "$bin" "$root/hil/$name"
  local libs
  libs=$(ldd "$bin" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\// {print $1}') || true
  for lib in $libs; do cp -L --parents "$lib" "$root"; done  # none for a static binary
}
copy_binary "$test_bin" hil_vcan_test
copy_binary "$sim_bin" visvol-hapticsim
copy_binary "$(command -v candump)" candump

cat >"$root/init" <<EOF
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin:/hil
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
for m in can can-raw can-dev vcan; do insmod /mod/\$m.ko || echo "insmod \$m failed"; done
ip link add dev vcan0 type vcan && ip link set up vcan0
export VISVOL_HIL_INTERFACE=vcan0 VISVOL_HAPTICSIM=/hil/visvol-hapticsim VISVOL_CANDUMP=/hil/candump
export VISVOL_HIL_TMP=/tmp VISVOL_HIL_SLACK_MS=$slack_ms VISVOL_HIL_TIMEOUT_MS=$timeout_ms
export ASAN_OPTIONS='${ASAN_OPTIONS:-}' UBSAN_OPTIONS='${UBSAN_OPTIONS:-}' GTEST_FILTER='${GTEST_FILTER:-*}'
echo "== guest: \$(uname -r), \$(nproc) CPU, vcan0 \$(cat /sys/class/net/vcan0/operstate 2>/dev/null)"
/hil/hil_vcan_test --gtest_color=no
echo "EXIT=\$?"
poweroff -f
EOF
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) >"$workdir/initrd.gz"
echo "== kernel $kernel, initramfs $(du -h "$workdir/initrd.gz" | cut -f1)"

# Boot: TCG, no network device at all, serial console on stdio.
start=$(date +%s.%N)
status=0
timeout -k 5 "$timeout_s" qemu-system-x86_64 -accel tcg -m 512 -smp 1 -nographic -no-reboot -nic none \
  -kernel "$kernel" -initrd "$workdir/initrd.gz" -append "console=ttyS0 quiet panic=-1" \
  </dev/null >"$workdir/console.log" 2>&1 || status=$?
end=$(date +%s.%N)
tr -d '\r' <"$workdir/console.log" | sed -n '/== guest/,$p'
echo "== VM: $(awk -v a="$start" -v b="$end" 'BEGIN {printf "%.1f", b - a}') s (boot, suite, power-off)"
result=$(tr -d '\r' <"$workdir/console.log" | sed -n 's/^EXIT=\([0-9]*\)$/\1/p' | tail -n 1)
if [[ -z $result ]]; then
  echo "hil_vcan_qemu: the VM did not report a result (qemu status $status; timeout ${timeout_s} s)" >&2
  tr -d '\r' <"$workdir/console.log" | tail -n 40 >&2
  exit 1
fi
exit "$result"
