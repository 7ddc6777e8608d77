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
No rclpy import here (PyYAML only, to check parameter files before rcl reads them).
"""

from __future__ import annotations

import ctypes
import faulthandler
import os
import signal
from collections.abc import Iterator, MutableMapping, Sequence
from contextlib import contextmanager
from types import FrameType

import yaml

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


#: Longest a process's ROS teardown (nodes destroyed, context shut down) may take [s].
SHUTDOWN_TIMEOUT_S = 5.0


@contextmanager
def bounded_teardown(timeout_s: float = SHUTDOWN_TIMEOUT_S) -> Iterator[None]:
    """Exit the process (status 1, every thread's stack on stderr) if the block hangs.

    Destroying a Fast DDS participant while one of its discovery callbacks runs can spin
    at 100 % of a core for good (Fast DDS issue 6513; seen here when an `rmcli topic pub`
    and the robot it fed stopped together: it ran on, orphaned, for 11 minutes). The
    stuck call holds the interpreter lock, so the watchdog is faulthandler's own C thread.
    Put only the teardown in the block, after the last messages are out.
    """
    faulthandler.dump_traceback_later(timeout_s, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def die_with_parent(parent_pid: int, signum: int = signal.SIGTERM) -> bool:
    """Have the kernel send this process signum when its parent dies, however it dies.

    A child of a process killed with SIGKILL would otherwise run on, orphaned (a second
    rm_sim beside the next robot's). Exits at once if the parent is already gone.

    Args:
        parent_pid: the pid of the parent that started this process.
        signum: the signal (SIGTERM: the clean shutdown path, see the module docstring).

    Returns:
        False where the kernel offers no such request (not Linux); True otherwise.
    """
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        prctl = libc.prctl
    except (OSError, AttributeError):
        return False
    if prctl(_PR_SET_PDEATHSIG, int(signum), 0, 0, 0) != 0:
        return False
    if os.getppid() != parent_pid:  # it died before the request was in place
        os._exit(1)
    return True


def init_error_line(err: BaseException) -> str:
    """One line for the operator from a failed ``rclpy.init``.

    rcl's message (e.g. for a params file that is not valid YAML) without the source
    locations it appends (``, at /project/src/...``).
    """
    text = ' '.join(str(err).split())
    return text.split(', at /', 1)[0].rstrip(' ,')


def params_file_error(args: Sequence[str]) -> str | None:
    """Check every ``--params-file`` in a ROS command line before rcl reads it.

    rcl logs an error of its own and raises a long message for a params file it cannot
    parse; this gives the operator one line naming the file and the place instead.

    Args:
        args: the process arguments (``sys.argv`` or what is passed to ``rclpy.init``).

    Returns:
        None if every params file is readable YAML without anchors, else one line.
    """
    files = [args[i + 1] for i, arg in enumerate(args[:-1]) if arg == '--params-file']
    for path in files:
        try:
            with open(path, encoding='utf-8') as stream:
                for event in yaml.parse(stream):
                    if isinstance(event, yaml.AliasEvent):
                        mark = event.start_mark
                        line = mark.line + 1 if mark is not None else 0
                        return (
                            f'{path}:{line}: YAML anchors and aliases are not supported in '
                            'ROS 2 parameter files; spell the values out'
                        )
        except OSError as err:
            return f'cannot read parameter file {path}: {err.strerror}'
        except yaml.YAMLError as err:
            mark = getattr(err, 'problem_mark', None)
            where = f'{path}:{mark.line + 1}:{mark.column + 1}' if mark else path
            problem = getattr(err, 'problem', None) or str(err)
            return f'{where}: not valid YAML: {problem}'
    return None
