"""The reference loops' CPU counts what each loop costs its process, as the robot's does.

The EventsExecutor runs its timers on a native thread of rclpy's; counting only the
executor's Python thread left that out of the reference (3.6 % of a core of its ~20 %).
"""

import pytest
from support.bench import bench_module


def _loop_cpu(per_thread, loop_thread):
    return bench_module('baseline').loop_cpu_percent(per_thread, loop_thread)


def test_the_events_executor_counts_its_native_timer_and_dds_threads():
    per_thread = {
        'bench-executor': 16.5, 'native:python': 3.6, 'native:dds.ev.0': 0.1,
        'bench-feeder': 4.8, 'MainThread': 0.2,
    }
    assert _loop_cpu(per_thread, 'bench-executor') == pytest.approx(20.2)


def test_the_scheduler_thread_counts_itself_and_its_helpers_not_the_bench():
    per_thread = {'can-scheduler': 21.3, 'rm_base-log': 0.4, 'bench-feeder': 5.0,
                  'MainThread': 0.1}
    assert _loop_cpu(per_thread, 'can-scheduler') == pytest.approx(21.7)


def test_no_loop_thread_is_no_cpu():
    assert _loop_cpu({'bench-feeder': 5.0, 'MainThread': 0.1}, 'bench-executor') == 0.0
