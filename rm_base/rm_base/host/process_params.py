"""The parameters of rm_robot's own process: its loop, its threads and its CPUs.

They matter only when rm_robot runs as a process of its own (the split robot); in the
one-process robot can_bridge's ``scheduler.*`` decide the same things
(docs/ARCHITECTURE.md, "Real-time priority").
"""

from __future__ import annotations

from dataclasses import dataclass

from rm_base.plugin import PluginParams
from rm_base.plugin.errors import ParameterError
from rm_base.runtime import cpu_latency
from rm_base.runtime.realtime import EDGE_PRIORITY, LOOP_PRIORITY, choose_cpu


@dataclass(frozen=True)
class ProcessSettings:
    """How rm_robot's own process runs its loop (see :func:`process_settings`).

    Attributes:
        loop_rate: the plugin loop's rate [Hz].
        loop_priority: the loop thread's SCHED_FIFO priority; 0: normal scheduling.
        edge_priority: the SCHED_FIFO priority of the process's other threads; 0: normal.
        cpu_index: the CPU every Python thread runs on (an index into the allowed ones);
            None: wherever the kernel puts them.
        cpu_latency_us: the wake-up latency asked of idle CPUs [µs]; None: no request.
    """

    loop_rate: float
    loop_priority: int
    edge_priority: int
    cpu_index: int | None
    cpu_latency_us: int | None


def process_settings(params: PluginParams) -> ProcessSettings:
    """Declare and read the process parameters of rm_robot (the node's own, no prefix).

    Raises:
        ParameterError: a value is out of range, or ``cpu`` names no CPU of the process.
    """
    loop_rate = params.double(
        'loop_rate',
        1000.0,
        description='rate of the plugin loop when rm_robot runs as a process of its own '
        '(in the one-process robot the CAN loop, scheduler.rate_hz, runs the plugins)',
        unit='Hz',
        gt=0.0,
        le=10000.0,
    )
    edge_priority = params.integer(
        'edge_priority',
        EDGE_PRIORITY,
        ge=0,
        le=99,
        description="real-time priority rm_robot gives the process's other threads, "
        'below the loop (a thread holding the GIL must not be preempted); 0: normal',
    )
    one_cpu = params.boolean(
        'one_cpu',
        True,
        description='rm_robot as a process of its own runs every Python thread on one CPU '
        "(cpu), where its loop keeps the GIL for its whole tick (the one-process robot "
        "follows can_bridge's scheduler.one_cpu)",
    )
    cpu = params.integer(
        'cpu',
        -2,
        description='with one_cpu, which CPU: an index into the CPUs the process may '
        "use, -2 the last but one (can_bridge's loop takes the last)",
    )
    try:
        choose_cpu(cpu)
    except ValueError as err:
        raise ParameterError(f'cpu: {err}') from err
    latency = params.integer(
        'cpu_latency_us',
        0,
        ge=-1,
        le=1_000_000,
        description='rm_robot as a process of its own asks the kernel to wake idle CPUs '
        'within this many microseconds (/dev/cpu_dma_latency; 0: idle CPUs poll); -1: no '
        'request',
    )
    loop_priority = params.integer(
        'loop_priority',
        LOOP_PRIORITY,
        ge=0,
        le=99,
        description='real-time (SCHED_FIFO) priority of the plugin loop thread when '
        'rm_robot runs as a process of its own; 0: normal scheduling',
    )
    return ProcessSettings(
        loop_rate=loop_rate,
        loop_priority=loop_priority,
        edge_priority=edge_priority,
        cpu_index=cpu if one_cpu else None,
        cpu_latency_us=cpu_latency.from_parameter(latency),
    )
