"""realtime: SCHED_FIFO for the loop, and below it for the process's other threads."""

import os
import threading

import pytest

from rm_base import realtime


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


def test_a_refusal_is_one_warning_and_normal_scheduling(monkeypatch, caplog):
    def refuse(priority):
        raise PermissionError(1, 'Operation not permitted')

    monkeypatch.setattr(realtime, 'raise_process_threads', refuse)
    with caplog.at_level('WARNING', logger='rm_base.realtime'):
        assert realtime.raise_edge_priority(10) is False
    assert 'SCHED_FIFO 10 refused' in caplog.text
    assert realtime.raise_edge_priority(0) is False  # 0: asked for nothing


@pytest.mark.skipif(not hasattr(os, 'sched_setscheduler'), reason='Linux scheduling API')
def test_the_calling_thread_gets_the_policy_when_permitted():
    result = {}

    def worker():
        try:
            realtime.set_fifo_priority(5)
        except PermissionError as err:  # an unprivileged machine: the call is refused
            result['refused'] = err
            return
        result['policy'] = os.sched_getscheduler(0)
        result['priority'] = os.sched_getparam(0).sched_priority

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join()
    assert 'refused' in result or (result['policy'], result['priority']) == (os.SCHED_FIFO, 5)
