"""rm_ros2 benchmarks (issue #7): ``make bench`` runs ``bench/run.py``.

Benchmarks are not tests: they print numbers and PASS/MISS against targets and never
assert on timing. One module per measurement:

* :mod:`bench.scheduler_timing` -- 1 kHz scheduler period error and missed deadlines;
* :mod:`bench.latency` -- command topic -> first CAN frame carrying the new target;
* :mod:`bench.cpu` -- CPU per component (thread groups of the one-process robot);
* :mod:`bench.throughput` -- feedback decode + dispatch rate, CPU per motor;
* :mod:`bench.baseline` -- the same loop on an rclpy timer (SingleThreadedExecutor).

Measurements 1-3 run on the whole standard robot (:mod:`bench.robot` drives
:mod:`bench.robot_proc` and :mod:`bench.commander` as child processes).
"""
