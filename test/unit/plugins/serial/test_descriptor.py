"""DescriptorReader on a real pseudo-terminal: nothing, data, a chunk at a time, a hang-up."""

import os

import pytest
import serial
from rm_plugins.serial.descriptor import DescriptorReader
from support.serial_port import Pty


@pytest.fixture
def pty(tmp_path):
    port = Pty(str(tmp_path / 'dev'))
    yield port
    port.close()


def opened(pty):
    # as the reader opens a port: pyserial, non-blocking, VMIN 0
    return serial.serial_for_url(pty.path, baudrate=115200, timeout=0.01)


def test_nothing_waiting_reads_empty_and_data_reads_whole(pty):
    port = opened(pty)
    reader = DescriptorReader(port.fileno(), 4)
    assert reader.read() == b''
    pty.write(b'abcdef')
    assert reader.read() == b'abcd'  # at most size bytes
    assert reader.read() == b'ef'
    assert reader.read() == b''
    port.close()


def test_a_terminal_whose_other_side_closed_is_an_error(pty):
    port = opened(pty)
    reader = DescriptorReader(port.fileno(), 64)
    os.close(pty.master)
    with pytest.raises(OSError):
        reader.read()
    port.close()


def test_a_closed_descriptor_is_an_error(pty):
    port = opened(pty)
    reader = DescriptorReader(port.fileno(), 64)
    port.close()
    with pytest.raises(OSError):
        reader.read()
