#!/usr/bin/env bash
# Run one command in the guest kernel (docs/KERNEL_CAN.md) and return its exit code:
#
#   scripts/kernel_run.sh 'ip link add dev vcan0 type vcan && candump -h'
#
# The guest boots Debian's kernel under QEMU's software emulation (TCG: this machine's
# /dev/kvm cannot run a stock kernel), with the host's / as its root (read-only, writes
# go to a tmpfs) and this repository at the same path, as root, with loopback up and
# vcan loaded; the command runs in bash from the repository root and its output is
# printed here when the guest is done. KERNEL_TIMEOUT (default 1200 s) bounds the whole boot. Set up first with
# scripts/kernel_setup.sh.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache=${RM_KERNEL_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/rm_ros2/kernel}
if ! why=$("$repo/scripts/kernel_setup.sh" --check); then
  echo "[kernel] not set up ($why): run scripts/kernel_setup.sh" >&2
  exit 3
fi
kver=$(cat "$cache/ready")
out=$(mktemp -d "${TMPDIR:-/tmp}/rm_kernel.XXXXXX")
trap 'rm -rf "$out"' EXIT
echo "$cache/root/lib/modules/$kver" > "$out/modules_dir"
{
  echo '#!/bin/bash'
  echo 'mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev'
  echo 'mkdir -p /dev/pts /dev/shm; mount -t devpts devpts /dev/pts; mount -t tmpfs tmpfs /dev/shm'
  # scratch space in the guest's memory; not over /tmp, where a clone may live (CI's)
  echo 'mount -t tmpfs tmpfs /run; mkdir -p /run/tmp; export TMPDIR=/run/tmp'
  # progress on the guest's console (kept when the guest fails, below)
  echo 'mark() { echo "[guest $(cut -d" " -f1 /proc/uptime) s] $*" > /dev/console; }'
  echo 'mark mounted'
  echo 'ip link set lo up; modprobe vcan; modprobe can_raw; mark "vcan loaded; command starts"'
  echo "export HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
  echo 'export PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1 RM_KERNEL_GUEST=1'
  # the caller's ROS isolation (network rule), unchanged
  for var in ROS_DOMAIN_ID ROS_AUTOMATIC_DISCOVERY_RANGE; do
    [ -n "${!var:-}" ] && printf 'export %s=%q\n' "$var" "${!var}"
  done
  printf 'cd %q\n' "$repo"
  printf 'bash -c %q < /dev/null > /kout/output 2>&1\n' "$*"
  echo 'rc=$?; mark "command ended: exit $rc"; echo $rc > /kout/rc'
  echo 'sync; echo o > /proc/sysrq-trigger; sleep 30'
} > "$out/guest.sh"
# one vCPU: with two the guest finds QEMU's TSCs unsynchronised and reads its clock from
# the emulated HPET, and about one run in three crawled (docs/KERNEL_CAN.md)
timeout "${KERNEL_TIMEOUT:-1200}" qemu-system-x86_64 -accel tcg -cpu max -smp 1 -m 4096 \
  -nographic -nodefaults -no-reboot -monitor none -serial "file:$out/console" \
  -kernel "$cache/root/boot/vmlinuz-$kver" -initrd "$cache/initramfs.gz" \
  -append 'console=ttyS0 quiet loglevel=3 panic=-1' \
  -virtfs local,path=/,mount_tag=host,security_model=none,readonly=on,multidevs=remap \
  -virtfs "local,path=$out,mount_tag=out,security_model=none" < /dev/null || true
# the command's output; the guest's console (firmware, kernel) only when it went wrong
[ -f "$out/output" ] && cat "$out/output"
if [ ! -f "$out/rc" ]; then
  echo '[kernel] the guest ended without an exit code (boot failed or timed out); its console:' >&2
  tr -d '\033' < "$out/console" | tail -n 30 >&2
  exit 4
fi
exit "$(cat "$out/rc")"
