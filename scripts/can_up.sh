#!/usr/bin/env bash
# Bring a robot's CAN interfaces up (docs/KERNEL_CAN.md, "A robot's CAN set-up"):
#
#   sudo scripts/can_up.sh can0 can1                    # candleLight / gs_usb, mttcan, MCP2515
#   sudo scripts/can_up.sh --slcan /dev/ttyACM0 can0    # a serial-line (slcan) adapter
#   scripts/can_up.sh --vcan vcan0                      # a virtual bus (tests, rm_sim)
#   scripts/can_up.sh --print can0                      # only say what it would run
#
# Options: --bitrate BIT/S (default 1000000, the RoboMaster motors' rate), --restart-ms MS
# (default 100: after a bus-off the controller restarts itself after this long; 0 would
# leave it off the bus until someone runs `ip link set can0 type can restart`),
# --txqueuelen N (default 1000 frames: the kernel's queue in front of the controller; the
# drivers' default of 10 overflows when a 1 kHz loop sends a burst to a slow bus).
set -euo pipefail
bitrate=1000000 restart_ms=100 txqueuelen=1000 mode=can slcan_tty='' dry=0
while [ $# -gt 0 ]; do
  case "$1" in
    --bitrate) bitrate=$2; shift 2 ;;
    --restart-ms) restart_ms=$2; shift 2 ;;
    --txqueuelen) txqueuelen=$2; shift 2 ;;
    --vcan) mode=vcan; shift ;;
    --slcan) mode=slcan; slcan_tty=$2; shift 2 ;;
    --print) dry=1; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    -*) echo "can_up: unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
if [ $# -eq 0 ]; then echo 'can_up: name at least one interface (can0 ...)' >&2; exit 2; fi
if [ "$mode" = slcan ] && [ $# -ne 1 ]; then
  echo 'can_up: --slcan attaches one adapter: one interface name' >&2; exit 2
fi

run() { echo "+ $*"; [ "$dry" = 1 ] || "$@"; }

# slcand's -s codes: the bitrates a serial-line adapter knows
slcan_speed() {
  case "$1" in
    10000) echo 0 ;; 20000) echo 1 ;; 50000) echo 2 ;; 100000) echo 3 ;; 125000) echo 4 ;;
    250000) echo 5 ;; 500000) echo 6 ;; 800000) echo 7 ;; 1000000) echo 8 ;;
    *) echo "can_up: slcan has no bitrate $1" >&2; return 1 ;;
  esac
}

for dev in "$@"; do
  case "$mode" in
    vcan)
      [ -e "/sys/class/net/$dev" ] || run ip link add dev "$dev" type vcan
      run ip link set dev "$dev" txqueuelen "$txqueuelen"
      ;;
    slcan)
      speed=$(slcan_speed "$bitrate")
      # -o open the channel, -c close it on exit, -s the bitrate; the adapter's own
      # serial speed does not matter over USB
      run slcand -o -c -s"$speed" "$slcan_tty" "$dev"
      [ "$dry" = 1 ] || for _ in $(seq 50); do [ -e "/sys/class/net/$dev" ] && break; sleep 0.1; done
      run ip link set dev "$dev" txqueuelen "$txqueuelen"
      ;;
    can)
      run ip link set dev "$dev" down
      run ip link set dev "$dev" type can bitrate "$bitrate" restart-ms "$restart_ms"
      run ip link set dev "$dev" txqueuelen "$txqueuelen"
      ;;
  esac
  run ip link set dev "$dev" up
done
[ "$dry" = 1 ] || for dev in "$@"; do ip -details link show dev "$dev"; done
