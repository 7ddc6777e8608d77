"""Real-time scheduling of the robot's threads (Linux SCHED_FIFO).

The control loop asks for SCHED_FIFO, as ros2_control's controller manager does for its
thread. In Python that is not enough: every thread of the process needs the interpreter
lock to run, and a thread that holds it while the kernel preempts it for another process
(the simulator, a vision pipeline) keeps the loop waiting for as long as it is not
scheduled, a priority inversion no lock protocol resolves. So the process's other
threads (executor, publishers, readers, DDS) run at a lower real-time priority than the
loop: above every normal process, below the loop. They are event-driven and woken after
the loop's ticks, so they use little CPU; the kernel's real-time throttling
(``sched_rt_runtime_us``) bounds them anyway.

And every Python thread of the process runs on one CPU (:func:`keep_on_cpu`). On two CPUs
at once the other threads run beside the loop and ask it for the GIL mid-tick (it must
drop it within the switch interval); on the loop's CPU they cannot run while the loop
does, since its priority is above theirs, so the loop keeps the GIL for its whole tick and
they run in its sleep. Native threads (DDS) need no GIL and stay free. Measured in
docs/PERFORMANCE.md.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

from rm_base.runtime import cpu_latency

_log = logging.getLogger(__name__)

#: Priority of the control loop thread (ros2_control's ``thread_priority`` default).
LOOP_PRIORITY = 50
#: Priority of every other thread of the robot's process.
EDGE_PRIORITY = 10
#: Longest a thread that wakes waits for the GIL behind a busy one (CPython: 5 ms) [s].
GIL_SWITCH_INTERVAL_S = 0.0005
#: The same in a loop's process that also hosts threads outside the robot
#: (:func:`outside_robot`): they hold the GIL whenever they run, and the loop, which
#: preempts them as it wakes, waits for it up to this long [s].
GIL_SWITCH_INTERVAL_BESIDE_OUTSIDE_S = 0.0001

_thread_role = threading.local()
# Native ids of this process's threads that are not the robot's (outside_robot).
_outside_robot: set[int] = set()
# Whether prepare_loop_process ran in this process.
_loop_process = [False]


@contextlib.contextmanager
def loop_thread() -> Iterator[None]:
    """Within it, the calling thread runs a control loop: nothing it calls may block on I/O.

    What could block goes to another thread instead: its log lines, for one
    (rm_base.ros.log), since rcutils sends each on /rosout in the caller's thread.
    """
    _thread_role.loop = True
    try:
        yield
    finally:
        _thread_role.loop = False


def in_loop_thread() -> bool:
    """Whether the calling thread is inside :func:`loop_thread`."""
    return getattr(_thread_role, 'loop', False)


def at_most_edge_priority() -> None:
    """Lower the calling thread to EDGE_PRIORITY if it runs above it (SCHED_FIFO).

    For an edge thread that the loop's thread starts: it inherits the loop's priority.
    """
    if os.sched_getscheduler(0) == os.SCHED_FIFO:
        if os.sched_getparam(0).sched_priority > EDGE_PRIORITY:
            set_fifo_priority(EDGE_PRIORITY)


@contextlib.contextmanager
def outside_robot() -> Iterator[None]:
    """Within it, the calling thread is not the robot's: normal scheduling, below all of them.

    For what shares a process with a loop but stands for something outside the robot: the
    physics of a simulated world (``sim: true``: the motors, which have CPUs of their own
    on a robot) and a test harness's own threads. At real-time priority beside the loop
    they took more than the 95 % of its CPU that the kernel leaves to real-time threads,
    and the kernel then stopped them all, the loop with them, for about 50 ms a second
    (docs/PERFORMANCE.md, "Real-time throttling"). Wrap the thread's whole body in it:
    :func:`raise_process_threads` leaves the thread as it is, and a thread started after
    the process was prepared drops the priority it inherited. It stays on the CPU it is
    given (:func:`keep_on_cpu` pins it with the loop): it takes the GIL, and there only the
    loop's own process preempts it, whose threads wait for that lock while it holds it. In
    a loop's process the switch interval becomes GIL_SWITCH_INTERVAL_BESIDE_OUTSIDE_S.
    """
    tid = threading.get_native_id()
    _outside_robot.add(tid)
    try:
        if os.sched_getscheduler(0) != os.SCHED_OTHER:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        _shorten_beside_outside_threads()
        yield
    finally:
        _outside_robot.discard(tid)  # the id may be reused by a later thread


def _shorten_beside_outside_threads() -> None:
    if _loop_process[0] and _outside_robot:
        sys.setswitchinterval(
            min(sys.getswitchinterval(), GIL_SWITCH_INTERVAL_BESIDE_OUTSIDE_S)
        )


def shorten_gil_switch_interval() -> None:
    """Lower the interpreter's GIL switch interval (process-wide) to GIL_SWITCH_INTERVAL_S."""
    sys.setswitchinterval(min(sys.getswitchinterval(), GIL_SWITCH_INTERVAL_S))


def set_fifo_priority(priority: int, thread_id: int = 0) -> None:
    """Put a thread (0: the calling one) under SCHED_FIFO at priority.

    Raises:
        OSError: not permitted (no CAP_SYS_NICE and no RLIMIT_RTPRIO for it), or no such
            thread.
    """
    os.sched_setscheduler(thread_id, os.SCHED_FIFO, os.sched_param(priority))


@contextlib.contextmanager
def children_start_normal() -> Iterator[None]:
    """Within it, a process the calling thread starts begins under normal scheduling.

    A child inherits its parent thread's policy and CPU. A Python node started from an
    edge thread would run its start-up (about a second of imports) at the edge priority,
    where SCHED_FIFO takes no turns, beside the threads the loop waits for
    (docs/RELIABILITY.md). SCHED_RESET_ON_FORK is set only meanwhile: it resets new
    threads too, and the process's later threads keep the edge priority.
    """
    policy = os.sched_getscheduler(0)
    if policy != os.SCHED_FIFO:  # normal already, or the flag set by a caller
        yield
        return
    param = os.sched_getparam(0)
    os.sched_setscheduler(0, policy | os.SCHED_RESET_ON_FORK, param)
    try:
        yield
    finally:
        os.sched_setscheduler(0, policy, param)


def raise_process_threads(priority: int) -> int:
    """Give every thread of this process that runs under normal scheduling SCHED_FIFO.

    Threads already real-time (the loop) keep their priority, and threads outside the
    robot (:func:`outside_robot`) normal scheduling; threads created later by one of
    them inherit the creator's policy (Linux' default for new threads).

    Returns:
        The number of threads changed.

    Raises:
        OSError: not permitted.
    """
    changed = 0
    for task in Path('/proc/self/task').iterdir():
        tid = int(task.name)
        if tid in _outside_robot:
            continue
        try:
            if os.sched_getscheduler(tid) == os.SCHED_FIFO:
                continue
            set_fifo_priority(priority, tid)
        except ProcessLookupError:  # the thread ended meanwhile
            continue
        changed += 1
    return changed


def choose_cpu(index: int) -> int | None:
    """The CPU at index among those the process may use (sorted; -1: the last).

    Returns:
        The CPU number, or None when the process may use only one CPU (nothing to choose).

    Raises:
        ValueError: index is outside the list of allowed CPUs.
    """
    allowed = sorted(os.sched_getaffinity(0))
    if len(allowed) < 2:
        return None
    if not -len(allowed) <= index < len(allowed):
        raise ValueError(
            f'CPU index {index} is outside the {len(allowed)} CPUs this process may use '
            f'({", ".join(map(str, allowed))}); -1 is the last'
        )
    return allowed[index]


def pin_python_threads(cpu: int) -> int:
    """Run every Python thread of this process on cpu; threads they start inherit it.

    Native threads (the DDS middleware's) stay where they are: they never take the GIL,
    and elsewhere they deliver messages while the loop runs.

    Returns:
        The number of threads moved.

    Raises:
        OSError: the kernel refused (e.g. a cpuset without that CPU).
    """
    moved = 0
    for thread in threading.enumerate():
        tid = thread.native_id
        if tid is None:  # not started yet: it will inherit its starter's CPU
            continue
        try:
            os.sched_setaffinity(tid, {cpu})
        except ProcessLookupError:  # the thread ended meanwhile
            continue
        moved += 1
    return moved


def keep_on_cpu(index: int) -> int | None:
    """Run the process's Python threads on the CPU at index (see :func:`choose_cpu`).

    Call it from an executable's main once its nodes (and their threads) exist, beside
    :func:`raise_edge_priority`. With one CPU there is nothing to choose; a refusal is
    one warning, and the threads run wherever the kernel puts them.

    Returns:
        The CPU the threads now run on, or None.

    Raises:
        ValueError: index is outside the allowed CPUs (a configuration error).
    """
    cpu = choose_cpu(index)
    if cpu is None:
        return None
    try:
        count = pin_python_threads(cpu)
    except OSError as err:
        _log.warning('threads not kept on CPU %d (%s): the loop may wait for the GIL '
                     'mid-tick; see docs/PERFORMANCE.md', cpu, err)
        return None
    _log.info('%d Python thread(s) of the process on CPU %d', count, cpu)
    return cpu


def raise_edge_priority(priority: int = EDGE_PRIORITY) -> bool:
    """Run the process's threads at real-time priority (see the module docstring).

    Call it from an executable's main once its nodes (and their threads) exist; 0 does
    nothing. Without the right to it, one warning and normal scheduling.

    Returns:
        Whether the threads now run at priority.
    """
    if priority <= 0:
        return False
    try:
        count = raise_process_threads(priority)
    except OSError as err:
        _log.warning(
            'threads keep normal scheduling (SCHED_FIFO %d refused: %s): a thread '
            'preempted while it holds the interpreter lock delays the loop; see '
            'docs/PERFORMANCE.md', priority, err,
        )
        return False
    _log.info('%d thread(s) of the process at SCHED_FIFO %d, below the loop', count, priority)
    return True


def hold_cpu_latency(max_us: int | None) -> bool:
    """Keep idle CPUs waking within max_us [µs] while the process runs (None: no request).

    See :mod:`rm_base.runtime.cpu_latency`. Without the right to it, one warning and no request.

    Returns:
        Whether the request is held.
    """
    if max_us is None:
        return False
    try:
        cpu_latency.hold(max_us)
    except OSError as err:
        _log.warning(
            'idle CPUs may sleep deeply (a wake-up latency of %d us refused: %s): the loop '
            'may wake late; see docs/PERFORMANCE.md', max_us, err,
        )
        return False
    _log.info('idle CPUs wake within %d us while the process runs (%s)', max_us, cpu_latency.PATH)
    return True


def prepare_loop_process(
    edge_priority: int, cpu_index: int | None, cpu_latency_us: int | None
) -> None:
    """Set up a process that runs a control loop, once its nodes (and threads) exist.

    What every executable that hosts a loop does, and what a harness that hosts one must do
    alike to measure the same thing: the GIL switch interval shortened
    (:func:`shorten_gil_switch_interval`), the other threads below the loop's priority
    (:func:`raise_edge_priority`), idle CPUs kept quick to wake (:func:`hold_cpu_latency`;
    None asks nothing) and every Python thread on one CPU (:func:`keep_on_cpu`; None leaves
    them where the kernel puts them).

    Raises:
        ValueError: cpu_index is outside the allowed CPUs (a configuration error).
    """
    _loop_process[0] = True
    shorten_gil_switch_interval()
    _shorten_beside_outside_threads()
    raise_edge_priority(edge_priority)
    hold_cpu_latency(cpu_latency_us)
    if cpu_index is not None:
        keep_on_cpu(cpu_index)
