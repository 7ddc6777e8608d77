#!/usr/bin/env bash
# The whole suite, as `make test` runs it: scripts/run_tests.sh [pytest arguments...]
#
# Two passes (docs/DEVELOPING.md, "Running the tests"): first every test that runs no
# robot in real time, spread over TEST_WORKERS pytest-xdist workers (default auto: one
# more than the CPUs), a test file per worker at a time; then the tests marked realtime,
# in this process, one after another, with nothing else of the suite running beside them.
# A marker expression of the caller's (-m EXPR) narrows both passes.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# Bytecode caches on, whatever the environment says: with PYTHONDONTWRITEBYTECODE set, every
# process of the suite (the workers' collection, each node and rmcli) compiled its sources
# anew, and pytest rewrote every test file's asserts in each pass (9 s against 3 s a pass).
export PYTHONDONTWRITEBYTECODE=
workers=${TEST_WORKERS:-auto}
if [ "$workers" = auto ]; then
  # Pass 1's tests wait on child processes and DDS discovery about as much as they
  # compute: one worker more than the CPUs keeps them busy (2 CPUs: 3:02 against 3:30-3:52).
  workers=$(( $(nproc) + 1 ))
fi
selection=''
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    -m) selection=$2; shift 2 ;;
    --markexpr=*) selection=${1#--markexpr=}; shift ;;
    -m*) selection=${1#-m}; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
within() {  # the pass's marker expression, within the caller's
  if [ -n "$selection" ]; then echo "($selection) and ($1)"; else echo "$1"; fi
}

status=0
empty=0
run() {
  scripts/with_env.sh python -m pytest "$@"
  local rc=$?
  if [ "$rc" -eq 5 ]; then  # this pass selected no test (the selection was the other's)
    empty=$((empty + 1))
  elif [ "$rc" -ne 0 ]; then
    status=$rc
  fi
}

echo "[test] pass 1 of 2: the tests that run no robot in real time, $workers worker(s)"
run -n "$workers" --dist loadfile -m "$(within 'not realtime')" ${args[@]+"${args[@]}"}

# The kernel CAN tier (docs/KERNEL_CAN.md), in a guest kernel, for the whole suite only,
# with RM_KERNEL_TESTS=1 where `make test-kernel` has set the guest up. Between the passes,
# alone: beside pass 1 the guest (software-emulated) slowed 10-fold and its waits ran out.
# Not by default: its ~4 minutes (the robot in lockstep, in the slow guest) would take
# make test past its 10-minute budget.
if [ "${RM_KERNEL_TESTS:-0}" != 1 ]; then
  echo '[test] kernel CAN tier not run: `make test-kernel` runs it (RM_KERNEL_TESTS=1: here)'
elif [ -z "$selection" ] && [ ${#args[@]} -eq 0 ]; then
  if why=$(scripts/kernel_setup.sh --check); then
    echo "[test] the kernel CAN tier, in a guest kernel (make test-kernel)"
    # README's command; bounded, so a guest that stalls cannot hold the suite up
    KERNEL_TIMEOUT=${KERNEL_TIMEOUT:-900} make --no-print-directory test-kernel
    rc=$?
    [ "$rc" -ne 0 ] && status=$rc
  else
    echo "[test] kernel CAN tier not run: $why (make test-kernel sets it up)"
  fi
fi
echo "[test] pass 2 of 2: the real-time tests, one at a time"
run -m "$(within realtime)" ${args[@]+"${args[@]}"}
if [ "$status" -eq 0 ] && [ "$empty" -eq 2 ]; then
  status=5  # neither pass selected a test: as pytest says for an empty selection
fi
exit "$status"
