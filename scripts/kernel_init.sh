#!/bin/busybox sh
# The guest kernel's /init (built into the initramfs by scripts/kernel_setup.sh): load the
# modules that reach the host, mount the host's / read-only over 9p under a tmpfs overlay,
# give it the guest kernel's modules, and hand over to the run's script (the "out" share's
# guest.sh, written by scripts/kernel_run.sh). A failure powers the guest off at once.
/bin/busybox --install -s /bin
mkdir -p /proc /sys /dev /lower /upper /newroot
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
fail() { echo "[guest init] $*"; echo o > /proc/sysrq-trigger; sleep 10; }
for ko in $(cat /modules/order); do
  insmod "/modules/$ko" || fail "insmod $ko failed"
done
mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=512000 host /lower || fail 'no host share'
mount -t tmpfs -o size=75% tmpfs /upper
mkdir -p /upper/data /upper/work
mount -t overlay overlay -o lowerdir=/lower,upperdir=/upper/data,workdir=/upper/work /newroot \
  || fail 'overlay failed'
mkdir -p /newroot/kout
mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 out /newroot/kout || fail 'no out share'
kver=$(uname -r)
kdir=$(cat /newroot/kout/modules_dir)
mkdir -p "/newroot/lib/modules/$kver"
mount --bind "/newroot$kdir" "/newroot/lib/modules/$kver"
umount /proc /sys
exec switch_root /newroot /bin/bash /kout/guest.sh
