"""InboxReport: the inbox's status on /diagnostics, WARN for what was lost since the last one."""

from types import SimpleNamespace

from diagnostic_msgs.msg import DiagnosticStatus
from rm_base.plugin.inbox_status import InboxReport


def inbox(taken, dropped, errors=0, receive_errors=0, pending=0, lost=None):
    return SimpleNamespace(taken_by_topic=taken, dropped_by_topic=dropped, errors=errors,
                           receive_errors=receive_errors, pending=pending,
                           lost_by_topic=lost or {})


def values(status):
    return {kv.key: kv.value for kv in status.values}


def test_when_nothing_was_lost_expect_ok_with_the_counts_per_topic():
    status = InboxReport('rm_robot').status(
        inbox({'/vel_cmd': 12, '/chassis_cmd': 3}, {'/vel_cmd': 0, '/chassis_cmd': 0},
              pending=1))
    assert (status.name, status.level, status.message, status.hardware_id) == (
        'rm_robot: inbox', DiagnosticStatus.OK, 'ok', 'inbox')
    assert values(status) == {
        '/chassis_cmd taken': '3', '/chassis_cmd dropped': '0', '/chassis_cmd lost': '0',
        '/vel_cmd taken': '12', '/vel_cmd dropped': '0', '/vel_cmd lost': '0',
        'pending': '1', 'take errors': '0', 'callback errors': '0',
    }


def test_when_messages_were_dropped_expect_warn_once_naming_the_topic_and_count():
    report = InboxReport('can_bridge')
    report.status(inbox({'/actuator_cmd': 10}, {'/actuator_cmd': 2}))
    status = report.status(inbox({'/actuator_cmd': 20}, {'/actuator_cmd': 5}))
    assert status.level == DiagnosticStatus.WARN
    assert status.message == 'since the last report: 3 on /actuator_cmd dropped'
    assert values(status)['/actuator_cmd dropped'] == '5'
    again = report.status(inbox({'/actuator_cmd': 30}, {'/actuator_cmd': 5}))
    assert (again.level, again.message) == (DiagnosticStatus.OK, 'ok')


def test_when_takes_or_callbacks_failed_expect_warn_with_each_count():
    report = InboxReport('rm_robot')
    status = report.status(inbox({'/a': 1}, {'/a': 0}, errors=2, receive_errors=1))
    assert status.level == DiagnosticStatus.WARN
    assert status.message == (
        'since the last report: 1 take(s) failed, 2 not handed out (callback failed)')


def test_when_dds_lost_messages_before_the_take_expect_warn_with_the_count():
    report = InboxReport('rm_robot')
    report.status(inbox({'/vel_cmd': 10}, {'/vel_cmd': 0}))
    status = report.status(inbox({'/vel_cmd': 20}, {'/vel_cmd': 0}, lost={'/vel_cmd': 7}))
    assert status.level == DiagnosticStatus.WARN
    assert status.message == 'since the last report: 7 on /vel_cmd lost before taken'
    assert values(status)['/vel_cmd lost'] == '7'
