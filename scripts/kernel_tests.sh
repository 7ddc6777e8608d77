#!/usr/bin/env bash
# The kernel CAN tier (docs/KERNEL_CAN.md): boot the guest kernel once and run the tests
# of test/kernel in it, on vcan, with can-utils; exit with pytest's status.
#
#   scripts/kernel_tests.sh [pytest arguments...]     # e.g. -k candump
#
# Needs scripts/kernel_setup.sh first (`make test-kernel` does both).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# (no arguments: none; printf would make one empty word of them, and pytest reads an
# empty path as the repository root: the whole suite in the guest)
args=''
[ $# -gt 0 ] && args=$(printf ' %q' "$@")
# -B: the host's tree is read-only in the guest; no plugin that writes a cache or forks
exec scripts/kernel_run.sh "scripts/with_env.sh python -B -m pytest -q -p no:cacheprovider \
-p no:randomly -p no:xdist --timeout 600 test/kernel$args"
