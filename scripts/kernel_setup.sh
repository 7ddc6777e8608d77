#!/usr/bin/env bash
# The kernel CAN tier's set-up (docs/KERNEL_CAN.md): qemu, can-utils and Debian's own
# kernel, extracted (not installed) into a cache, with an initramfs that boots it on the
# host's / (read-only over 9p, under a tmpfs overlay).
#
#   scripts/kernel_setup.sh           # set up (idempotent: a second run only checks)
#   scripts/kernel_setup.sh --check   # exit 0 if set up, else 1 and one line why
#
# The cache is $RM_KERNEL_CACHE, else ${XDG_CACHE_HOME:-~/.cache}/rm_ros2/kernel; it is
# shared by every clone on the machine. Installing the host packages needs root and apt.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

cache=${RM_KERNEL_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/rm_ros2/kernel}
packages=(qemu-system-x86 can-utils kmod cpio iproute2)
tools=(qemu-system-x86_64 candump canplayer cangen modprobe cpio ip)
log() { echo "[kernel-setup] $*"; }

missing_tools() {
  local t out=()
  for t in "${tools[@]}"; do command -v "$t" >/dev/null 2>&1 || out+=("$t"); done
  echo "${out[*]}"
}

if [ "${1:-}" = --check ]; then
  gone=$(missing_tools)
  if [ -n "$gone" ]; then echo "missing on this machine: $gone"; exit 1; fi
  if [ ! -f "$cache/ready" ]; then echo "no guest kernel in $cache"; exit 1; fi
  exit 0
fi

start=$(date +%s)
gone=$(missing_tools)
if [ -n "$gone" ]; then
  if [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null; then
    echo "[kernel-setup] needs ${packages[*]} (apt, as root); missing: $gone" >&2
    exit 1
  fi
  log "apt-get install ${packages[*]}"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    "${packages[@]}" >/dev/null
fi

if [ -f "$cache/ready" ]; then
  log "ready: $(cat "$cache/ready") in $cache"
  exit 0
fi

rm -rf "$cache.partial"
mkdir -p "$cache.partial/debs" "$cache.partial/root"
cd "$cache.partial/debs"
# Debian's current kernel, the one linux-image-amd64 points at
image=$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-/ {print $2; exit}')
log "apt-get download $image busybox-static"
# root downloads into its own cache; apt's sandbox user could not write there
apt-get download -qq -o APT::Sandbox::User=root "$image" busybox-static
cd "$cache.partial"
for deb in debs/*.deb; do dpkg-deb -x "$deb" root; done
kver=${image#linux-image-}
depmod -b root "$kver"

# The initramfs: a static busybox, the modules that reach the host's / (virtio, 9p,
# overlay) in load order, and init (scripts/kernel_init.sh).
initrd=$cache.partial/initrd
mkdir -p "$initrd/bin" "$initrd/modules"
cp root/bin/busybox "$initrd/bin/busybox"
: > "$initrd/modules/order"
# (--show-depends takes one module; further words would be its parameters)
for mod in virtio_pci 9pnet_virtio 9p overlay; do
  modprobe -d root -S "$kver" --show-depends "$mod"
done | awk '$1 == "insmod" {print $2}' | while read -r ko; do
    name=$(basename "$ko")
    grep -qx "$name" "$initrd/modules/order" && continue
    cp "$ko" "$initrd/modules/$name"
    echo "$name" >> "$initrd/modules/order"
  done
cp "$here/kernel_init.sh" "$initrd/init"
chmod +x "$initrd/init"
(cd "$initrd" && find . | cpio -o -H newc --quiet | gzip -1) > initramfs.gz
rm -rf "$initrd" debs
echo "$kver" > ready
rm -rf "$cache"
mv "$cache.partial" "$cache"
log "ready: $kver in $cache ($(( $(date +%s) - start )) s)"
