"""Process set-up shared by the rm_ros2 node executables (rm_robot, can_bridge).

Call ``prepare_ros_process()`` first thing in ``main()``, before ``rclpy.init``:

- DDS discovery stays on this machine unless the user chose otherwise
  (``ROS_AUTOMATIC_DISCOVERY_RANGE`` is only set when unset).
- SIGTERM raises ``KeyboardInterrupt`` like SIGINT does, so ``ros2 launch`` stopping a
  node runs the same clean shutdown path.

Pair it with ``rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)``:
rclpy's own SIGINT handler shuts the context down before ``main`` regains control
(verified on rclpy 7.1.6: a publish in the ``finally`` block then fails with "publisher's
context is invalid"), so a node could not command zero output on the way down. With
Python's default handler the KeyboardInterrupt reaches ``main`` while the context still
works; ``main`` publishes its last messages, then calls ``rclpy.try_shutdown()``.
No rclpy import here.
"""

from __future__ import annotations

import os
import signal
from collections.abc import MutableMapping
from types import FrameType

DISCOVERY_RANGE_VAR = 'ROS_AUTOMATIC_DISCOVERY_RANGE'


def use_localhost_discovery(environ: MutableMapping[str, str] | None = None) -> str:
    """Set ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST unless already set; return the value.

    Args:
        environ: environment to change; default ``os.environ``.
    """
    environ = os.environ if environ is None else environ
    return environ.setdefault(DISCOVERY_RANGE_VAR, 'LOCALHOST')


def _raise_keyboard_interrupt(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt(f'signal {signal.Signals(signum).name}')


def prepare_ros_process(environ: MutableMapping[str, str] | None = None) -> None:
    """Localhost discovery by default, and SIGTERM handled like SIGINT (see module doc)."""
    use_localhost_discovery(environ)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _raise_keyboard_interrupt)
