"""ROS helpers for tests: isolated environment, private contexts, waiting on conditions.

Every ROS process a test starts runs with localhost-only discovery and the session's own
ROS_DOMAIN_ID (set by test/conftest.py before anything imports rclpy, claimed with a lock
file so that no two test sessions on one machine share it), so parallel runs never
cross-talk and no DDS traffic leaves the machine.
"""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

TEST_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Domain 42 is the interactive default of scripts/env.sh; tests keep away from it.
_USER_DOMAIN = 42


_DOMAINS = 101  # ids 1..101: the range ROS 2 recommends, ephemeral ports stay clear
# Test sessions on one machine claim their domain with a lock file here (any clone).
_CLAIMS = os.path.join(tempfile.gettempdir(), 'rm_ros2_test_domains')
# The claim of this process: held open (locked) until the process ends.
_CLAIMED: list[Any] = []


def pick_domain_id(seed: int) -> int:
    """Return a ROS domain id in 1..101 derived from seed, never the interactive default."""
    domain = 1 + seed % _DOMAINS
    return domain + 1 if domain == _USER_DOMAIN else domain


def claim_domain_id(seed: int) -> int:
    """Return a domain id no other test session on this machine holds, and hold it.

    Starts at ``pick_domain_id(seed)`` and takes the first id whose lock file under
    /tmp it can lock (``fcntl.flock``; the kernel drops the lock when the process ends,
    however it ends). Two sessions with colliding seeds (1 in 101 for two pids) would
    otherwise share DDS topics and the simulator's IMU terminal.
    """
    os.makedirs(_CLAIMS, exist_ok=True)
    first = pick_domain_id(seed)
    for step in range(_DOMAINS):
        domain = pick_domain_id(first - 1 + step)
        claim = open(os.path.join(_CLAIMS, f'{domain}.lock'), 'a')
        try:
            fcntl.flock(claim, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            claim.close()
            continue
        _CLAIMED.append(claim)
        return domain
    raise RuntimeError(f'all {_DOMAINS} ROS domains are held by other test sessions')


def domain_claim_fds() -> list[int]:
    """The file descriptors of this process's domain claims, for its children to inherit.

    A child started with them (``pass_fds``) holds the claim too: a child that outlives
    its parent (the parent killed before its clean-up) keeps its domain from the next
    test session, which would otherwise hear its topics and services.
    """
    return [claim.fileno() for claim in _CLAIMED]


def isolate_ros_environment(environ: dict[str, str] | os._Environ) -> int:
    """Force localhost-only discovery, a private domain id and ROS_HOME into environ.

    Returns the domain id. ROS_HOME is one temporary folder per test session.

    A domain already chosen through RM_TEST_DOMAIN_ID is kept, so a test process and the
    processes it starts agree; but a pytest-xdist worker (``PYTEST_XDIST_WORKER``) claims
    one of its own, since tests on two workers run at once and must not hear each other.
    RM_TEST_DOMAIN_OWNER names the worker that claimed it ('' for a session without
    workers), so the processes a worker starts keep the worker's domain.
    """
    environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    # ROS's folder for a node's files (logs, the configs' calibration files): the test
    # process's own, never the user's ~/.ros
    if not environ.get('RM_TEST_ROS_HOME'):
        environ['RM_TEST_ROS_HOME'] = tempfile.mkdtemp(prefix='rm_test_ros_home_')
    environ['ROS_HOME'] = environ['RM_TEST_ROS_HOME']
    worker = environ.get('PYTEST_XDIST_WORKER', '')
    chosen = environ.get('RM_TEST_DOMAIN_ID')
    if environ.get('RM_TEST_DOMAIN_OWNER', '') != worker:
        chosen = None  # the xdist controller's, inherited by this worker
    domain = int(chosen or claim_domain_id(os.getpid()))
    environ['RM_TEST_DOMAIN_OWNER'] = worker
    environ['RM_TEST_DOMAIN_ID'] = str(domain)
    environ['ROS_DOMAIN_ID'] = str(domain)
    return domain


def wait_until(
    predicate: Callable[[], bool],
    timeout: float,
    *,
    spin: Callable[[float], None] | None = None,
    period: float = 0.01,
) -> bool:
    """Poll predicate until it is true or timeout [s] passes; return its last value.

    Args:
        predicate: condition to wait for.
        timeout: longest wait [s]; generous values keep tests stable under CPU steal.
        spin: called with a short timeout [s] between polls (e.g. executor.spin_once),
            so callbacks run while waiting. Without it the thread sleeps for period.
        period: poll period [s] when spin is None.
    """
    deadline = time.monotonic() + timeout
    while True:
        if predicate():
            return True
        if time.monotonic() >= deadline:
            return bool(predicate())
        if spin is not None:
            spin(period)
        else:
            time.sleep(period)


def spin_until(node: Any, ready: Callable[[], bool], timeout: float = 5.0) -> bool:
    """Spin node alone (its own executor) until ready() or timeout [s]; return ready()."""
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    try:
        return wait_until(lambda: executor.spin_once(timeout_sec=0.01) or ready(), timeout)
    finally:
        executor.remove_node(node)


def call_idempotent(executor: Any, client: Any, request: Any, attempts: int = 4,
                    timeout_s: float = 5.0) -> Any:
    """Call a service whose request may be repeated; the response, or None after every try.

    A service can be discovered (``wait_for_service``) before it has matched the client's
    response reader, and a request sent then gets no answer (seen once in a fresh-clone CI
    run: no response within 20 s). A repeated request after a few seconds is answered.
    """
    for _ in range(attempts):
        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=timeout_s)
        if future.done() and future.result() is not None:
            return future.result()
        client.remove_pending_request(future)
    return None


@contextmanager
def rclpy_context() -> Iterator[object]:
    """Yield a private, initialised rclpy Context on the test domain; shut it down after."""
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
    try:
        yield context
    finally:
        context.try_shutdown()


def start_process(args: Sequence[str], **kwargs) -> subprocess.Popen:
    """Start a child process in the isolated ROS environment (stdout/stderr captured).

    The test tree is put on the child's PYTHONPATH, so `python -m support.<module>` works;
    the child holds this session's domain claim (:func:`domain_claim_fds`).
    """
    env = dict(os.environ)
    env.update(kwargs.pop('env', {}))
    isolate_ros_environment(env)
    env['PYTHONPATH'] = os.pathsep.join(p for p in (TEST_ROOT, env.get('PYTHONPATH')) if p)
    pass_fds = [*kwargs.pop('pass_fds', ()), *domain_claim_fds()]
    return subprocess.Popen(
        list(args), env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        pass_fds=pass_fds, **kwargs,
    )


def stop_process(proc: subprocess.Popen, timeout: float = 10.0) -> tuple[str, str]:
    """Send SIGINT, wait up to timeout [s] (then kill); return (stdout, stderr)."""
    if proc.poll() is None:
        proc.send_signal(subprocess.signal.SIGINT)
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.communicate()


def run_rmcli(*args: str, timeout: float = 30.0) -> tuple[int, str, str]:
    """Run ``rmcli args...`` in a child process (this session's domain); its code, out, err."""
    proc = start_process([sys.executable, '-m', 'rm_bringup.cli', *args])
    out, err = proc.communicate(timeout=timeout)
    return proc.returncode, out, err


@contextmanager
def spinning(node: Any) -> Iterator[Any]:
    """Spin node in a thread of its own while the block runs (a node others call)."""
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    try:
        yield node
    finally:
        executor.shutdown()
        thread.join(5.0)
