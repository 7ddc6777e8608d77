#!/usr/bin/env bash
# The whole suite, as `make test` runs it: scripts/run_tests.sh [pytest arguments...]
#
# Two passes (docs/DEVELOPING.md, "Running the tests"): first every test that runs no
# robot in real time, spread over TEST_WORKERS pytest-xdist workers (default auto: one
# per CPU), a test file per worker at a time; then the tests marked realtime, in this
# process, one after another, with nothing else of the suite running beside them.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

workers=${TEST_WORKERS:-auto}
status=0
empty=0

run() {
  scripts/with_env.sh python -m pytest "$@"
  local rc=$?
  if [ "$rc" -eq 5 ]; then  # this pass selected no test (-k matched the other's only)
    empty=$((empty + 1))
  elif [ "$rc" -ne 0 ]; then
    status=$rc
  fi
}

echo "[test] pass 1 of 2: the tests that run no robot in real time, $workers worker(s)"
run -n "$workers" --dist loadfile -m 'not realtime' "$@"
echo "[test] pass 2 of 2: the real-time tests, one at a time"
run -m realtime "$@"
if [ "$status" -eq 0 ] && [ "$empty" -eq 2 ]; then
  status=5  # neither pass selected a test: as pytest says for an empty selection
fi
exit "$status"
