"""spin_until_shutdown: a signal ends the loop between callbacks, never inside one."""

import os
import signal

import pytest
from rm_base.ros.node_main import spin_until_shutdown


class AlwaysOk:
    def ok(self):
        return True


class SignallingExecutor:
    """Its first spin_once receives a signal midway, as a Ctrl-C during a callback."""

    def __init__(self, signum):
        self.signum = signum
        self.started = 0
        self.finished = 0

    def spin_once(self, timeout_sec):
        self.started += 1
        os.kill(os.getpid(), self.signum)
        sum(range(10_000))  # Python code runs on in the callback: the handler runs here
        self.finished += 1


def _raise_keyboard_interrupt(signum, frame):
    raise KeyboardInterrupt


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_when_a_signal_arrives_during_a_callback_expect_it_to_finish_then_the_loop_to_end(signum):
    # as prepare_ros_process() leaves them: both raise KeyboardInterrupt
    previous = {s: signal.signal(s, _raise_keyboard_interrupt)
                for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        executor = SignallingExecutor(signum)
        spin_until_shutdown(executor, AlwaysOk(), timeout_sec=0.01)
        assert (executor.started, executor.finished) == (1, 1)
        # the handlers are back: a signal now interrupts as before
        assert signal.getsignal(signum) is _raise_keyboard_interrupt
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def test_when_on_tick_returns_false_expect_the_loop_to_end():
    class Idle:
        calls = 0

        def spin_once(self, timeout_sec):
            self.calls += 1

    executor = Idle()
    spin_until_shutdown(executor, AlwaysOk(), on_tick=lambda: executor.calls < 3)
    assert executor.calls == 3


def test_a_sigint_while_the_node_starts_up_still_stops_it_cleanly(monkeypatch):
    from rm_base.ros import node_main

    calls = []

    class Node:
        edge_priority = 0
        cpu_index = None
        cpu_latency_us = None
        context = None

        def shutdown(self):
            calls.append('shutdown')

        def destroy_node(self):
            calls.append('destroy')

    class Executor:
        def add_node(self, node):
            pass

        def shutdown(self):
            calls.append('executor')

    def interrupted(priority, cpu_index, cpu_latency_us):
        raise KeyboardInterrupt  # Ctrl-C after the loop started, before the spin

    monkeypatch.setattr(node_main, 'init_ros', lambda name, args: True)
    monkeypatch.setattr(node_main, 'prepare_loop_process', interrupted)
    try:
        status = node_main.run_node('n', [], Node, lambda node: Executor())
    except KeyboardInterrupt:
        pytest.fail('the interrupt escaped run_node: no zero output, a traceback')
    assert status == 0
    assert calls == ['shutdown', 'executor', 'destroy']
