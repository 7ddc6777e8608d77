"""CommandReport: the plugins' refused commands, counted per plugin and topic."""

import logging

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import TwistStamped
from rm_base.plugin.command_status import CommandReport
from rm_base.plugin.commands import CommandInput, InputRejectedError

S = 1_000_000_000


def refuse_odd(msg):
    if msg.header.stamp.nanosec % 2:
        raise InputRejectedError('odd nanoseconds')
    return msg


def command(sec, nanosec=0):
    msg = TwistStamped()
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
    return msg


def values(status):
    return {kv.key: kv.value for kv in status.values}


def test_new_rejections_warn_with_the_newest_reason_then_the_count_stays():
    log = logging.getLogger('test_command_status')
    chassis = CommandInput('/chassis_cmd', 0.5, log, parse=refuse_odd)
    gimbal = CommandInput('/gimbal_cmd', 0.5, log)
    report = CommandReport('rm_robot')
    inputs = [('chassis', chassis), ('gimbal', gimbal)]

    first = report.status(inputs)
    assert first.name == 'rm_robot: commands'
    assert (first.level, first.message) == (
        DiagnosticStatus.OK, 'no command rejected since the last report')
    assert values(first) == {'chassis /chassis_cmd rejected': '0',
                             'gimbal /gimbal_cmd rejected': '0',
                             'rejected since the last report': ''}

    assert not chassis.handle(command(100, 1), 100 * S)         # invalid
    assert chassis.handle(command(100, 2), 100 * S)             # valid: the count stays
    assert not gimbal.handle(command(90), 100 * S)              # 10 s old
    assert not gimbal.handle(command(101), 100 * S)             # 1 s in the future
    second = report.status(inputs)
    assert second.level == DiagnosticStatus.WARN
    assert second.message == (
        'rejected since the last report: 1 on /chassis_cmd (chassis), the newest: rejected '
        '/chassis_cmd: odd nanoseconds; 2 on /gimbal_cmd (gimbal), the newest: stale: stamp '
        'is 1.000 s in the future (clocks out of sync?), timeout 0.500 s')
    assert values(second) == {'chassis /chassis_cmd rejected': '1',
                              'gimbal /gimbal_cmd rejected': '2',
                              'rejected since the last report': '/chassis_cmd,/gimbal_cmd'}

    third = report.status(inputs)
    assert third.level == DiagnosticStatus.OK
    assert values(third) == {**values(second), 'rejected since the last report': ''}
