"""SocketCAN error frames decoded as linux/can/error.h defines them (docs/PROTOCOLS.md §7)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from rm_base.hardware.protocols import can_error
from rm_base.hardware.protocols.can_error import CanErrorReport, decode_error_frame

HEADER = Path('/usr/include/linux/can/error.h')


@pytest.mark.parametrize(('can_id', 'data', 'expected', 'line'), [
    # a driver's bus-off: class bit only
    (0x040, bytes(8), CanErrorReport(('bus-off',)), 'bus-off'),
    # a controller gone error-passive on transmit, with its counters (tx 128, rx 3)
    (0x204, bytes([0, 0x20, 0, 0, 0, 0, 128, 3]),
     CanErrorReport(('controller', 'counters'), controller=('tx-passive',),
                    tx_errors=128, rx_errors=3),
     'controller counters, controller tx-passive, counters tx 128 rx 3'),
    # a stuff error while transmitting, in the data field, reported as a bus error
    (0x088, bytes([0, 0, 0x84, 0x0A, 0, 0, 0, 0]),
     CanErrorReport(('protocol', 'bus-error'), protocol=('stuff', 'while-transmitting'),
                    location='data'),
     'protocol bus-error, protocol stuff while-transmitting at data'),
    # no ACK (nobody else on the bus), short data
    (0x020, b'', CanErrorReport(('no-ack',)), 'no-ack'),
    # back to error-active after a restart
    (0x104, bytes([0, 0x40]), CanErrorReport(('controller', 'restarted'), controller=('active',)),
     'controller restarted, controller active'),
    # a location not in the table is shown as its number
    (0x008, bytes([0, 0, 0x01, 0x0B]),
     CanErrorReport(('protocol',), protocol=('bit',), location='location 0x0B'),
     'protocol, protocol bit at location 0x0B'),
    # flags of a class not set are not read
    (0x001, bytes([0, 0xFF, 0xFF, 0xFF, 0, 0, 9, 9]), CanErrorReport(('tx-timeout',)),
     'tx-timeout'),
])
def test_error_frames_decode(can_id, data, expected, line):
    report = decode_error_frame(can_id, data)
    assert report == expected
    assert report.describe() == line
    assert report.bus_off == (can_id & 0x40 != 0)


@pytest.mark.skipif(not HEADER.exists(), reason='no kernel headers (linux-libc-dev)')
def test_the_tables_are_the_kernels():
    defines = dict(re.findall(r'#define (CAN_ERR_\w+)\s+(0x[0-9A-Fa-f]+)', HEADER.read_text()))
    value = {name: int(v.rstrip('Uu'), 16) for name, v in defines.items()}
    assert [bit for bit, _ in can_error.CLASSES] == [
        value[f'CAN_ERR_{n}'] for n in ('TX_TIMEOUT', 'LOSTARB', 'CRTL', 'PROT', 'TRX', 'ACK',
                                        'BUSOFF', 'BUSERROR', 'RESTARTED', 'CNT')]
    assert [bit for bit, _ in can_error.CONTROLLER] == [
        value[f'CAN_ERR_CRTL_{n}'] for n in ('RX_OVERFLOW', 'TX_OVERFLOW', 'RX_WARNING',
                                             'TX_WARNING', 'RX_PASSIVE', 'TX_PASSIVE', 'ACTIVE')]
    assert [bit for bit, _ in can_error.PROTOCOL] == [
        value[f'CAN_ERR_PROT_{n}'] for n in ('BIT', 'FORM', 'STUFF', 'BIT0', 'BIT1', 'OVERLOAD',
                                             'ACTIVE', 'TX')]
    locations = {'start of frame': 'SOF', 'CRC sequence': 'CRC_SEQ', 'data': 'DATA',
                 'CRC delimiter': 'CRC_DEL', 'ACK slot': 'ACK', 'end of frame': 'EOF',
                 'ACK delimiter': 'ACK_DEL', 'intermission': 'INTERM'}
    assert {name: code for code, name in can_error.LOCATION.items()} == {
        name: value[f'CAN_ERR_PROT_LOC_{n}'] for name, n in locations.items()}
