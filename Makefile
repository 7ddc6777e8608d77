# rm_ros2 — the two commands a user needs are `make run` and `make test`.
# Both set the workspace up on first use (scripts/setup.sh is idempotent and fast when
# nothing changed). Every ROS process started from here runs with localhost-only DDS
# discovery (scripts/env.sh), unless ROS_AUTOMATIC_DISCOVERY_RANGE is already set.

ROBOT ?= standard
PYTEST_ARGS ?=
# pytest-xdist workers of the suite's first pass: auto = one more than the CPUs; 0 = this process
export TEST_WORKERS ?= auto

.PHONY: all setup test test-kernel run lint lock clean bench meter soak

all: test

setup:
	@scripts/setup.sh

## test: the whole suite (unit, integration, replay, linters), each test once
test: setup
	@scripts/run_tests.sh $(PYTEST_ARGS)

## test-kernel: the kernel CAN tier in a guest kernel (installs qemu, can-utils and the
## guest's kernel on first use: docs/KERNEL_CAN.md)
test-kernel: setup
	@scripts/kernel_setup.sh
	@scripts/kernel_tests.sh $(PYTEST_ARGS)

## run: the standard robot on the simulated CAN bus (ROBOT=hero for the hero)
run: setup
	@scripts/with_env.sh bringup --robot $(ROBOT) --sim

lint: setup
	@scripts/with_env.sh ruff check .

bench: setup
	@scripts/with_env.sh python bench/run.py $(BENCH_ARGS)

## meter: CPU per loop component in lockstep (METER_ARGS='--against 8a56e03' for an A/B)
meter: setup
	@scripts/with_env.sh python bench/meter.py $(METER_ARGS)

soak: setup
	@scripts/with_env.sh python test/soak/run_soak.py $(SOAK_ARGS)

## lock: regenerate requirements/lock.txt from a fresh venv built from requirements.in
lock:
	rm -rf .venv-lock && python3.11 -m venv .venv-lock
	.venv-lock/bin/python -m pip install --quiet -r requirements/requirements.in
	.venv-lock/bin/python scripts/make_lock.py
	rm -rf .venv-lock

clean:
	-.venv/bin/python scripts/build_compiled.py --clean
	rm -rf build install log .venv .pytest_cache .ruff_cache .hypothesis
