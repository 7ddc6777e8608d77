"""Keep idle CPUs quick to wake while a control loop runs (Linux PM QoS).

A CPU with nothing to run enters an idle state, and leaving a deep one takes time. In a
virtual machine an idle vCPU halts, and the host may give its core to other work. The
loop, which sleeps between its ticks, then wakes late and runs its tick on cold caches
(docs/PERFORMANCE.md, "Idle CPUs poll").

A process that writes a latency [µs] to ``/dev/cpu_dma_latency`` and keeps the file open
asks the kernel for at most that wake-up latency on every CPU; 0 keeps idle CPUs polling
instead of halting. The request lasts while the file is open, and the kernel drops it when
the process exits. cyclictest does the same by default, and RHEL for Real Time documents
it. The price: idle CPUs keep running (power and heat; on a VM, the host's CPU time).
Writing the file needs root (or a udev rule that lets the robot's group write it).
"""

from __future__ import annotations

import os
import struct

#: The kernel's PM QoS file for the CPUs' wake-up latency.
PATH = '/dev/cpu_dma_latency'

# Files held open for the life of the process; a request ends when its file closes.
_held: list[int] = []


def from_parameter(value: int) -> int | None:
    """A ``cpu_latency_us`` parameter as a request [µs]: None (no request) for -1."""
    return None if value < 0 else value


def hold(max_us: int, path: str | None = None) -> None:
    """Ask for every CPU to wake within max_us [µs] until the process exits.

    Args:
        max_us: the longest wake-up latency allowed, >= 0; 0 keeps idle CPUs polling.
        path: the PM QoS file; None: :data:`PATH`.

    Raises:
        ValueError: max_us is negative.
        OSError: the file cannot be opened or written (not root, no such file).
    """
    if max_us < 0:
        raise ValueError(f'a wake-up latency must be >= 0 us, not {max_us}')
    # not inherited: a child (rm_sim) must not keep the request after the robot exits
    fd = os.open(path or PATH, os.O_WRONLY | os.O_CLOEXEC)
    try:
        os.write(fd, struct.pack('=i', max_us))  # the kernel reads a native s32
    except OSError:
        os.close(fd)
        raise
    _held.append(fd)


def release() -> None:
    """End every request this process holds (tests; exiting does it anyway)."""
    while _held:
        os.close(_held.pop())


def held() -> int:
    """How many requests this process holds."""
    return len(_held)
