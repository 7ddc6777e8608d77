"""The kernel's view of a SocketCAN interface, from `ip -details -statistics -json link`."""

from __future__ import annotations

import json

import pytest
from rm_base.hardware.can_link import LinkReader, LinkReport, link_is_up, parse_ip_link

# A USB adapter's controller (gs_usb) gone error-passive; the layout iproute2 prints.
CAN0 = [{
    'ifindex': 3, 'ifname': 'can0', 'flags': ['NOARP', 'UP', 'LOWER_UP', 'ECHO'], 'mtu': 16,
    'operstate': 'UP', 'txqlen': 1000, 'link_type': 'can',
    'linkinfo': {
        'info_kind': 'can',
        'info_data': {'state': 'ERROR-PASSIVE', 'berr_counter': {'tx': 136, 'rx': 0},
                      'restart_ms': 100,
                      'bittiming': {'bitrate': 1000000, 'sample_point': '0.875'}},
        'info_xstats': {'restarts': 1, 'bus_error': 12, 'arbitration_lost': 0,
                        'error_warning': 2, 'error_passive': 1, 'bus_off': 1},
    },
    'stats64': {'rx': {'bytes': 800, 'packets': 100, 'errors': 3, 'dropped': 2,
                       'over_errors': 1, 'multicast': 0},
                'tx': {'bytes': 80, 'packets': 10, 'errors': 0, 'dropped': 0,
                       'carrier_errors': 0, 'collisions': 0}},
}]
# vcan0 taken down: no controller, no CAN state
VCAN_DOWN = [{
    'ifindex': 4, 'ifname': 'vcan0', 'flags': ['NOARP'], 'mtu': 72, 'operstate': 'DOWN',
    'linkinfo': {'info_kind': 'vcan'},
    'stats64': {'rx': {'packets': 5, 'errors': 0, 'dropped': 0, 'over_errors': 0},
                'tx': {'packets': 7, 'errors': 0, 'dropped': 0}},
}]


def test_a_controller_reports_state_counters_and_restarts():
    report = parse_ip_link(json.dumps(CAN0))
    assert report == LinkReport(
        exists=True, up=True, kind='can', can_state='ERROR-PASSIVE', tx_error_counter=136,
        rx_error_counter=0, restart_ms=100, bitrate=1000000,
        counters={'rx_packets': 100, 'rx_errors': 3, 'rx_dropped': 2, 'rx_over_errors': 1,
                  'tx_packets': 10, 'tx_errors': 0, 'tx_dropped': 0,
                  'bus_off': 1, 'error_passive': 1, 'error_warning': 2, 'bus_error': 12,
                  'arbitration_lost': 0, 'restarts': 1})
    assert not report.healthy


def test_a_vcan_has_a_link_and_counters_only():
    report = parse_ip_link(json.dumps(VCAN_DOWN))
    assert (report.up, report.kind, report.can_state, report.restart_ms) == (
        False, 'vcan', '', None)
    assert report.tx_error_counter is None and report.counters['tx_packets'] == 7
    assert not report.healthy
    up = dict(VCAN_DOWN[0], flags=['NOARP', 'UP', 'LOWER_UP'])
    assert parse_ip_link(json.dumps([up])).healthy


@pytest.mark.parametrize('text', ['', 'Device "x" does not exist.', '[]', '{}', '[1]'])
def test_anything_else_is_refused(text):
    with pytest.raises(ValueError, match='ip -json link'):
        parse_ip_link(text)


def test_link_is_up_reads_the_flags_in_sysfs(tmp_path):
    (tmp_path / 'vcan0').mkdir()
    (tmp_path / 'vcan0' / 'flags').write_text('0x1\n')
    (tmp_path / 'vcan1').mkdir()
    (tmp_path / 'vcan1' / 'flags').write_text('0x80\n')
    assert link_is_up('vcan0', tmp_path) is True
    assert link_is_up('vcan1', tmp_path) is False
    assert link_is_up('can9', tmp_path) is None


def test_the_reader_asks_each_interface_at_most_once_a_period():
    asked = []
    now = [0.0]

    def read(interface):
        asked.append(interface)
        return LinkReport(exists=True, up=True)

    reader = LinkReader(read, period_s=1.0, clock=lambda: now[0])
    assert reader.report('can0').up
    now[0] = 0.5
    reader.report('can0')
    reader.report('can1')
    now[0] = 1.2
    reader.report('can0')
    assert asked == ['can0', 'can1', 'can0']
