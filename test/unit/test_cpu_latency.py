"""The PM QoS request that keeps idle CPUs quick to wake (rm_base.runtime.cpu_latency)."""

import os
import struct
import subprocess
import sys

import pytest
from rm_base.runtime import cpu_latency


@pytest.fixture(autouse=True)
def _released():
    yield
    cpu_latency.release()


def test_the_request_is_the_latency_as_the_kernels_s32_and_the_file_stays_open(tmp_path):
    # a plain file stands in for /dev/cpu_dma_latency: it keeps what was written
    path = tmp_path / 'cpu_dma_latency'
    path.write_bytes(b'')
    cpu_latency.hold(20, str(path))
    assert path.read_bytes() == struct.pack('=i', 20)
    assert cpu_latency.held() == 1
    cpu_latency.release()
    assert cpu_latency.held() == 0


def test_the_request_is_not_inherited_by_a_child(tmp_path):
    # rm_sim, started by bringup, must not keep the request alive after the robot exits
    path = tmp_path / 'cpu_dma_latency'
    path.write_bytes(b'')
    cpu_latency.hold(0, str(path))
    [fd] = cpu_latency._held
    assert not os.get_inheritable(fd)
    # close_fds=False: only the descriptor's own close-on-exec flag keeps it from the child
    child = subprocess.run(
        [sys.executable, '-c', f'import os; os.fstat({fd})'], close_fds=False, check=False,
        capture_output=True,
    )
    assert child.returncode != 0  # EBADF: the child has no such descriptor


@pytest.mark.parametrize('value, asked', [(-1, None), (0, 0), (50, 50)])
def test_minus_one_asks_nothing(value, asked):
    assert cpu_latency.from_parameter(value) == asked


def test_a_negative_latency_is_refused_before_the_file_is_opened(tmp_path):
    with pytest.raises(ValueError, match='>= 0'):
        cpu_latency.hold(-5, str(tmp_path / 'absent'))
    assert cpu_latency.held() == 0


def test_a_file_that_cannot_be_opened_raises_and_holds_nothing(tmp_path):
    with pytest.raises(FileNotFoundError):
        cpu_latency.hold(0, str(tmp_path / 'absent'))
    assert cpu_latency.held() == 0
