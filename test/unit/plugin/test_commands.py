"""CommandInput: stamps, staleness, timeout, "no command" logged once. No ROS."""

import pytest
from geometry_msgs.msg import Twist
from rm_base.errors import InputRejectedError
from rm_base.plugin import CommandInput, CommandStatus, LatestMessage, LogThrottle

from rm_msgs.msg import ChassisCmd

MS = 1_000_000  # [ns]
S = 1_000_000_000  # [ns]
T0 = 1_000 * S  # an arbitrary "now" well after the epoch [ns]


class RecordingLogger:
    def __init__(self):
        self.lines = []

    def info(self, message, **kwargs):
        self.lines.append(('info', message))

    def warning(self, message, **kwargs):
        self.lines.append(('warning', message))


def chassis_cmd(stamp_ns, mode=ChassisCmd.RAW):
    msg = ChassisCmd(mode=mode)
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, S)
    return msg


@pytest.fixture
def log():
    return RecordingLogger()


@pytest.fixture
def command(log):
    return CommandInput('/chassis_cmd', 0.1, log)


def test_a_fresh_command_is_returned(command):
    msg = chassis_cmd(T0)
    assert command.handle(msg, receive_ns=T0 + 5 * MS)
    assert command.latest(T0 + 50 * MS) is msg


def test_timeout_counts_from_the_stamp_not_from_reception(command):
    # Stamped at T0, received 60 ms later: with a 100 ms timeout it is valid until T0+100 ms.
    command.handle(chassis_cmd(T0), receive_ns=T0 + 60 * MS)
    assert command.latest(T0 + 100 * MS) is not None
    assert command.latest(T0 + 101 * MS) is None


def test_when_stamp_is_zero_expect_receive_time_used(command):
    msg = chassis_cmd(0)
    command.handle(msg, receive_ns=T0)
    assert command.stamp_ns() == T0
    assert command.latest(T0 + 100 * MS) is msg
    assert command.latest(T0 + 101 * MS) is None


def test_when_message_has_no_header_expect_receive_time_used(log):
    command = CommandInput('/vel_cmd', 0.1, log)
    twist = Twist()
    command.handle(twist, receive_ns=T0)
    assert command.latest(T0 + 99 * MS) is twist


def test_when_stamp_is_older_than_timeout_expect_rejected_and_logged(command, log):
    # 150 ms old on arrival > 100 ms timeout.
    assert not command.handle(chassis_cmd(T0), receive_ns=T0 + 150 * MS)
    assert command.rejected == 1
    assert command.status(T0 + 150 * MS)[0] is CommandStatus.NEVER_RECEIVED
    assert log.lines == [
        ('warning', 'rejected stale command on /chassis_cmd: stamp is 0.150 s old, timeout 0.100 s')
    ]


def test_a_stale_command_does_not_replace_a_fresh_one(command):
    fresh = chassis_cmd(T0, mode=ChassisCmd.FOLLOW)
    command.handle(fresh, receive_ns=T0)
    command.handle(chassis_cmd(T0 - 500 * MS, mode=ChassisCmd.GYRO), receive_ns=T0 + 1 * MS)
    assert command.latest(T0 + 2 * MS) is fresh


def test_when_stamp_is_in_the_future_beyond_timeout_expect_rejected(command, log):
    assert not command.handle(chassis_cmd(T0 + 2 * S), receive_ns=T0)
    assert 'in the future' in log.lines[0][1]


def test_a_stamp_a_little_in_the_future_lives_one_timeout_from_its_receipt(command):
    # The finding: a stamp up to one timeout ahead kept a command alive ~0.43 s after the
    # last message (0.25 s timeout + the stamp's lead).
    msg = chassis_cmd(T0 + 90 * MS)
    assert command.handle(msg, receive_ns=T0)
    assert command.latest(T0 + 100 * MS) is msg
    assert command.latest(T0 + 101 * MS) is None


def test_stale_rejections_are_logged_at_most_once_a_second(command, log):
    for i in range(10):  # ten stale messages within 90 ms
        command.handle(chassis_cmd(T0), receive_ns=T0 + S + i * 10 * MS)
    assert len(log.lines) == 1
    command.handle(chassis_cmd(T0), receive_ns=T0 + 2 * S + 1)
    assert len(log.lines) == 2
    assert log.lines[1][1].endswith('(9 more since the last report)')


def test_before_any_command_expect_no_command_reason(command):
    assert command.status(T0) == (CommandStatus.NEVER_RECEIVED, 'no command on /chassis_cmd yet')
    assert command.latest(T0) is None


def test_past_the_timeout_expect_reason_with_age_and_timeout(command):
    command.handle(chassis_cmd(T0), receive_ns=T0)
    status, reason = command.status(T0 + 250 * MS)
    assert status is CommandStatus.TIMED_OUT
    assert reason == 'no command on /chassis_cmd for 0.250 s (timeout 0.100 s)'


def test_no_command_is_logged_once_and_the_return_once(command, log):
    command.handle(chassis_cmd(T0), receive_ns=T0)
    for i in range(5):  # five ticks past the timeout
        assert command.latest(T0 + 200 * MS + i * MS) is None
    command.handle(chassis_cmd(T0 + 300 * MS), receive_ns=T0 + 300 * MS)
    for i in range(5):
        assert command.latest(T0 + 301 * MS + i * MS) is not None
    assert log.lines == [
        ('warning', 'no command on /chassis_cmd for 0.200 s (timeout 0.100 s)'),
        ('info', 'command on /chassis_cmd resumed'),
    ]


def test_clear_forgets_the_command(command):
    command.handle(chassis_cmd(T0), receive_ns=T0)
    command.clear()
    assert command.latest(T0 + 1 * MS) is None
    assert command.stamp_ns() is None


def test_when_timeout_is_not_positive_expect_value_error(log):
    with pytest.raises(ValueError, match='timeout of /x must be > 0 s'):
        CommandInput('/x', 0.0, log)


def test_latest_message_keeps_the_newest_with_its_stamp_or_receive_time():
    stamped = ChassisCmd()
    stamped.header.stamp.sec, stamped.header.stamp.nanosec = 2, 5
    unstamped = Twist()
    latest = LatestMessage()
    assert latest.get() is None
    latest.put(stamped, 9_000_000_000)
    assert latest.get() == (stamped, 2_000_000_005)  # the header stamp
    latest.put(unstamped, 9_000_000_000)
    assert latest.get() == (unstamped, 9_000_000_000)  # no header: the receive time
    by_arrival = LatestMessage(use_stamp=False)
    by_arrival.put(stamped, 7)
    assert by_arrival.get() == (stamped, 7)


def test_log_throttle_lets_one_line_through_per_period_and_counts_the_rest():
    throttle = LogThrottle(1_000)
    assert throttle.due(0) == ''
    assert throttle.due(10) is None and throttle.due(999) is None
    assert throttle.due(1_000) == ' (2 more since the last report)'
    assert throttle.due(2_000) == ''


def test_a_message_is_parsed_once_and_an_invalid_one_never_replaces_the_last_valid(log):
    parsed = []

    def parse(msg):
        parsed.append(msg)
        if msg.mode > ChassisCmd.POSITION:
            raise InputRejectedError(f'unknown mode {msg.mode}')
        return ('request', msg.mode)

    command = CommandInput('/chassis_cmd', 0.1, log, parse=parse)
    assert command.handle(chassis_cmd(T0), receive_ns=T0)
    for i in range(1, 4):  # a flood of invalid ones: one line, every one counted
        assert not command.handle(chassis_cmd(T0 + i * MS, mode=9), receive_ns=T0 + i * MS)
    assert len(parsed) == 4 and command.rejected == 3
    rejected = [line for line in log.lines if 'rejected' in line[1]]
    assert rejected == [('warning', 'rejected /chassis_cmd: unknown mode 9; the last valid '
                         'command stands until its timeout')]
    # the record, not the message, and taking it parses nothing again
    assert command.latest(T0 + 50 * MS) == ('request', ChassisCmd.RAW)
    assert len(parsed) == 4
    # the last valid one times out from its own stamp; the reason says what came since
    assert command.latest(T0 + 101 * MS) is None
    assert command.check(T0 + 101 * MS) == (
        'no valid command on /chassis_cmd for 0.101 s (timeout 0.100 s) since: rejected '
        '/chassis_cmd: unknown mode 9'
    )


def test_a_rejection_while_there_is_no_command_gives_the_episode_its_reason(log):
    def parse(msg):
        raise InputRejectedError('never valid')

    command = CommandInput('/chassis_cmd', 0.1, log, parse=parse)
    assert command.check(T0) == 'no command on /chassis_cmd yet'
    command.handle(chassis_cmd(T0), receive_ns=T0)
    assert command.check(T0 + MS) == 'rejected /chassis_cmd: never valid'
    command.handle(chassis_cmd(T0 + 2 * MS), receive_ns=T0 + 2 * MS)
    assert command.check(T0 + 3 * MS) == 'rejected /chassis_cmd: never valid'  # no new one
    # one bad message, one warning: the episode's start does not repeat the rejection's line
    warnings = [m for kind, m in log.lines if kind == 'warning']
    assert warnings == [
        'no command on /chassis_cmd yet',
        'rejected /chassis_cmd: never valid; no valid command has come yet',
    ]
    # after clear() (a plugin enabled again) the same rejection is news again
    command.clear()
    command.handle(chassis_cmd(T0 + 2_000 * MS), receive_ns=T0 + 2_000 * MS)
    assert command.check(T0 + 2_001 * MS) == 'rejected /chassis_cmd: never valid'
    assert [m for kind, m in log.lines if kind == 'warning'][2:] == [
        'rejected /chassis_cmd: never valid; no valid command has come yet '
        '(1 more since the last report)',
    ]
