"""The kernel CAN tier: tests on the kernel's SocketCAN (vcan, can-utils, python-can's
socketcan), which `make test-kernel` runs in a guest kernel (scripts/kernel_run.sh;
docs/KERNEL_CAN.md). On a kernel without AF_CAN they are skipped, saying so."""

from __future__ import annotations

import os
import socket
import subprocess
import uuid

import pytest


def _has_af_can() -> bool:
    try:
        socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
    except (OSError, AttributeError):
        return False
    return True


HAS_AF_CAN = _has_af_can()


def pytest_collection_modifyitems(config, items):
    if HAS_AF_CAN:
        return
    skip = pytest.mark.skip(reason="needs the kernel's SocketCAN: `make test-kernel` runs "
                            'these in a guest kernel')
    for item in items:
        if '/test/kernel/' in str(item.fspath):
            item.add_marker(skip)


def pytest_runtest_logreport(report):
    """In the guest, a failure is printed as it happens: a guest that stalls later and
    is cut by its timeout never reaches pytest's summary, and the first failure is
    the one that explains the rest."""
    if report.failed and os.environ.get('RM_KERNEL_GUEST'):
        reporter = _CONFIG[0].pluginmanager.get_plugin('terminalreporter')
        reporter.write_line(f'\n[kernel] {report.nodeid} failed in {report.when}:')
        reporter.write_line(report.longreprtext)


_CONFIG: list[pytest.Config] = []


def pytest_configure(config):
    _CONFIG.append(config)


def ip(*args: str) -> None:
    subprocess.run(['ip', *args], check=True, capture_output=True, text=True)


@pytest.fixture
def vcan():
    """A vcan interface of the test's own, up; deleted after."""
    name = f'vt{uuid.uuid4().hex[:8]}'
    ip('link', 'add', 'dev', name, 'type', 'vcan')
    ip('link', 'set', 'up', name)
    yield name
    subprocess.run(['ip', 'link', 'del', name], check=False, capture_output=True)


@pytest.fixture
def vcan2(vcan):
    """A second one, for a replay from one into the other."""
    name = f'vt{uuid.uuid4().hex[:8]}'
    ip('link', 'add', 'dev', name, 'type', 'vcan')
    ip('link', 'set', 'up', name)
    yield vcan, name
    subprocess.run(['ip', 'link', 'del', name], check=False, capture_output=True)
