"""realtime: SCHED_FIFO for the loop, and below it for the process's other threads."""

import logging
import os
import subprocess
import sys
import threading

import pytest
from rm_base.runtime import realtime


def test_raise_process_threads_changes_only_threads_under_normal_scheduling(monkeypatch):
    policies = {}
    changed = []
    monkeypatch.setattr(realtime.os, 'sched_getscheduler', lambda tid: policies.get(tid, 0))
    monkeypatch.setattr(
        realtime, 'set_fifo_priority', lambda priority, tid: changed.append((tid, priority))
    )
    stop = threading.Event()
    worker = threading.Thread(target=stop.wait)
    worker.start()
    try:
        policies[worker.native_id] = os.SCHED_FIFO  # the loop: keeps its own priority
        count = realtime.raise_process_threads(10)
    finally:
        stop.set()
        worker.join()
    tids = {tid for tid, _ in changed}
    assert threading.get_native_id() in tids and worker.native_id not in tids
    assert count == len(changed) and all(p == 10 for _, p in changed)


def test_raise_process_threads_leaves_a_thread_outside_the_robot(monkeypatch):
    changed = []
    monkeypatch.setattr(realtime.os, 'sched_getscheduler', lambda tid: os.SCHED_OTHER)
    monkeypatch.setattr(realtime, 'set_fifo_priority', lambda priority, tid: changed.append(tid))
    inside, stop = threading.Event(), threading.Event()

    def simulated_world():
        with realtime.outside_robot():
            inside.set()
            stop.wait()

    worker = threading.Thread(target=simulated_world)
    worker.start()
    try:
        inside.wait()
        realtime.raise_process_threads(10)
    finally:
        stop.set()
        worker.join()
    assert threading.get_native_id() in changed and worker.native_id not in changed
    assert worker.native_id not in realtime._outside_robot  # a new thread may reuse the id


def test_a_refusal_is_one_warning_and_normal_scheduling(monkeypatch, caplog):
    def refuse(priority):
        raise PermissionError(1, 'Operation not permitted')

    monkeypatch.setattr(realtime, 'raise_process_threads', refuse)
    with caplog.at_level('WARNING', logger='rm_base.runtime.realtime'):
        assert realtime.raise_edge_priority(10) is False
    assert 'SCHED_FIFO 10 refused' in caplog.text
    assert realtime.raise_edge_priority(0) is False  # 0: asked for nothing


def _in_a_real_time_thread(body):
    """body(result) in a new thread at SCHED_FIFO 5; result['refused'] where not permitted."""
    result = {}

    def worker():
        try:
            realtime.set_fifo_priority(5)
        except PermissionError as err:  # an unprivileged machine: the call is refused
            result['refused'] = err
            return
        body(result)

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join()
    return result


@pytest.mark.skipif(not hasattr(os, 'sched_setscheduler'), reason='Linux scheduling API')
def test_the_calling_thread_gets_the_policy_when_permitted():
    def body(result):
        result['policy'] = os.sched_getscheduler(0)
        result['priority'] = os.sched_getparam(0).sched_priority

    result = _in_a_real_time_thread(body)
    assert 'refused' in result or (result['policy'], result['priority']) == (os.SCHED_FIFO, 5)


def test_a_cpu_is_chosen_by_its_index_among_the_allowed_ones(monkeypatch):
    monkeypatch.setattr(realtime.os, 'sched_getaffinity', lambda pid: {4, 1, 7})
    assert realtime.choose_cpu(-1) == 7
    assert realtime.choose_cpu(-2) == 4
    assert realtime.choose_cpu(0) == 1
    with pytest.raises(ValueError, match=r'CPU index 3 is outside the 3 CPUs .*\(1, 4, 7\)'):
        realtime.choose_cpu(3)
    with pytest.raises(ValueError, match='-1 is the last'):
        realtime.choose_cpu(-4)


def test_with_one_allowed_cpu_there_is_nothing_to_choose_or_pin(monkeypatch):
    monkeypatch.setattr(realtime.os, 'sched_getaffinity', lambda pid: {0})
    monkeypatch.setattr(realtime, 'pin_python_threads', pytest.fail)
    assert realtime.choose_cpu(-1) is None
    assert realtime.choose_cpu(5) is None
    assert realtime.keep_on_cpu(-1) is None


def test_every_python_thread_of_the_process_moves_to_the_cpu(monkeypatch):
    moved = {}
    monkeypatch.setattr(
        realtime.os, 'sched_setaffinity', lambda tid, cpus: moved.update({tid: cpus})
    )
    stop = threading.Event()
    worker = threading.Thread(target=stop.wait)
    worker.start()
    try:
        count = realtime.pin_python_threads(3)
    finally:
        stop.set()
        worker.join()
    assert {threading.get_native_id(), worker.native_id} <= set(moved)
    assert count == len(moved) and all(cpus == {3} for cpus in moved.values())


def test_a_refused_pinning_is_one_warning(monkeypatch, caplog):
    monkeypatch.setattr(realtime.os, 'sched_getaffinity', lambda pid: {0, 1})

    def refuse(cpu):
        raise PermissionError(1, 'Operation not permitted')

    monkeypatch.setattr(realtime, 'pin_python_threads', refuse)
    with caplog.at_level('WARNING', logger='rm_base.runtime.realtime'):
        assert realtime.keep_on_cpu(-1) is None
    assert 'threads not kept on CPU 1' in caplog.text


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason='needs two CPUs to move between')
def test_a_thread_pinned_in_a_child_process_runs_on_that_cpu():
    # in a child, so the test session's own threads stay where they are
    import subprocess
    import sys

    cpu = sorted(os.sched_getaffinity(0))[-1]
    code = (
        'import os, threading; from rm_base.runtime import realtime\n'
        't = threading.Thread(target=threading.Event().wait, args=(0.5,)); t.start()\n'
        'cpu = realtime.keep_on_cpu(-1)\n'
        'print(cpu, os.sched_getaffinity(t.native_id) == {cpu}, os.sched_getaffinity(0) == {cpu})\n'
    )
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == [str(cpu), 'True', 'True']


def test_a_loop_process_gets_the_short_switch_interval_the_edge_priority_and_its_cpu(
    monkeypatch,
):
    calls = []
    monkeypatch.setattr(realtime, 'raise_edge_priority', lambda p: calls.append(('fifo', p)))
    monkeypatch.setattr(realtime, 'keep_on_cpu', lambda i: calls.append(('cpu', i)))
    monkeypatch.setattr(realtime.cpu_latency, 'hold', lambda us: calls.append(('latency', us)))
    monkeypatch.setattr(realtime, '_loop_process', [False])  # this test's process only
    before = sys.getswitchinterval()
    sys.setswitchinterval(0.005)  # CPython's default: a busy thread keeps a waking loop 5 ms
    try:
        realtime.prepare_loop_process(10, -1, 0)
        assert sys.getswitchinterval() == pytest.approx(realtime.GIL_SWITCH_INTERVAL_S)
        # no CPU and no latency asked for: the threads stay put, the CPUs idle as they will
        realtime.prepare_loop_process(0, None, None)
    finally:
        sys.setswitchinterval(before)
    assert calls == [('fifo', 10), ('latency', 0), ('cpu', -1), ('fifo', 0)]


def test_a_thread_outside_the_robot_in_a_loop_process_shortens_the_switch_interval(
    monkeypatch,
):
    monkeypatch.setattr(realtime, 'raise_edge_priority', lambda p: None)
    monkeypatch.setattr(realtime, '_loop_process', [False])
    before = sys.getswitchinterval()
    try:
        sys.setswitchinterval(0.005)
        with realtime.outside_robot():  # no loop in the process yet: nothing to shorten
            assert sys.getswitchinterval() == pytest.approx(0.005)
            realtime.prepare_loop_process(0, None, None)
            assert sys.getswitchinterval() == pytest.approx(
                realtime.GIL_SWITCH_INTERVAL_BESIDE_OUTSIDE_S
            )
        sys.setswitchinterval(0.005)
        realtime.prepare_loop_process(0, None, None)  # no thread outside it any more
        assert sys.getswitchinterval() == pytest.approx(realtime.GIL_SWITCH_INTERVAL_S)
        with realtime.outside_robot():  # one that starts after the process was prepared
            assert sys.getswitchinterval() == pytest.approx(
                realtime.GIL_SWITCH_INTERVAL_BESIDE_OUTSIDE_S
            )
    finally:
        sys.setswitchinterval(before)


def test_a_refused_latency_request_is_one_warning_and_the_process_goes_on(
    monkeypatch, tmp_path, caplog
):
    # not root: /dev/cpu_dma_latency is root's alone (crw-------)
    monkeypatch.setattr(realtime.cpu_latency, 'PATH', str(tmp_path / 'no_such_file'))
    with caplog.at_level(logging.WARNING, logger=realtime.__name__):
        assert realtime.hold_cpu_latency(0) is False
    assert realtime.cpu_latency.held() == 0
    [record] = caplog.records
    assert 'idle CPUs may sleep deeply' in record.getMessage()
    assert 'no_such_file' in record.getMessage()


@pytest.mark.skipif(not hasattr(os, 'SCHED_RESET_ON_FORK'), reason='Linux scheduling API')
def test_a_process_started_by_a_real_time_thread_within_children_start_normal_is_normal():
    def policy_of_a_child():
        child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(10)'])
        try:
            return os.sched_getscheduler(child.pid)
        finally:
            child.kill()
            child.wait()

    def body(result):
        result['inherited'] = policy_of_a_child()
        with realtime.children_start_normal():
            result['started normal'] = policy_of_a_child()
        result['thread after'] = _policy_of_a_new_thread()

    result = _in_a_real_time_thread(body)
    if 'refused' not in result:
        assert result['inherited'] == os.SCHED_FIFO  # what a child gets without it
        assert result['started normal'] == os.SCHED_OTHER
        # the flag also resets new threads: threads started afterwards inherit FIFO again
        assert result['thread after'] == os.SCHED_FIFO


@pytest.mark.skipif(not hasattr(os, 'sched_setscheduler'), reason='Linux scheduling API')
def test_a_thread_outside_the_robot_started_by_a_real_time_one_runs_normal_within():
    def body(result):
        def world():
            result['inherited'] = os.sched_getscheduler(0)
            with realtime.outside_robot():
                result['within'] = os.sched_getscheduler(0)

        thread = threading.Thread(target=world)
        thread.start()
        thread.join()

    result = _in_a_real_time_thread(body)
    if 'refused' not in result:
        assert result['inherited'] == os.SCHED_FIFO
        assert result['within'] == os.SCHED_OTHER


def _policy_of_a_new_thread():
    out = []
    thread = threading.Thread(target=lambda: out.append(os.sched_getscheduler(0)))
    thread.start()
    thread.join()
    return out[0]


def test_loop_thread_marks_only_the_calling_thread_and_only_within():
    seen = []
    with realtime.loop_thread():
        seen.append(realtime.in_loop_thread())
        other = threading.Thread(target=lambda: seen.append(realtime.in_loop_thread()))
        other.start()
        other.join()
    seen.append(realtime.in_loop_thread())
    assert seen == [True, False, False]


def test_at_most_edge_priority_lowers_a_thread_above_it_and_leaves_others(monkeypatch):
    set_to = []
    monkeypatch.setattr(realtime, 'set_fifo_priority', lambda p, tid=0: set_to.append(p))
    monkeypatch.setattr(realtime.os, 'sched_getscheduler', lambda tid: os.SCHED_FIFO)
    for priority in (realtime.LOOP_PRIORITY, realtime.EDGE_PRIORITY):
        monkeypatch.setattr(realtime.os, 'sched_getparam',
                            lambda tid, p=priority: os.sched_param(p))
        realtime.at_most_edge_priority()
    monkeypatch.setattr(realtime.os, 'sched_getscheduler', lambda tid: os.SCHED_OTHER)
    realtime.at_most_edge_priority()
    assert set_to == [realtime.EDGE_PRIORITY]
