"""The bridge's /actuator_cmd input: applied whole or refused whole, and counted."""

from rm_base.bridge.command_input import ActuatorCmdInput
from rm_base.joints import JointTarget, Mode

from rm_msgs.msg import ActuatorCmd

NOW_NS = 1_800_000_000_000_000_000


class Hardware:
    def __init__(self):
        self.targets = []

    def set_target(self, name, target, *, age_ns=0):
        self.targets.append((name, target, age_ns))


def velocity(joints, stamp_ns=0, states_ns=0):
    msg = ActuatorCmd()
    msg.name = list(joints)
    msg.mode = [ActuatorCmd.MODE_VELOCITY] * len(joints)
    msg.velocity = [float(v) for v in joints.values()]
    for field in ('position', 'effort', 'kp', 'kd'):
        setattr(msg, field, [0.0] * len(joints))
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
    msg.states_stamp.sec, msg.states_stamp.nanosec = divmod(states_ns, 1_000_000_000)
    return msg


def make():
    hardware, warnings = Hardware(), []
    commands = ActuatorCmdInput(
        hardware, ['fl', 'fr'], 0.1, lambda: NOW_NS, warnings.append
    )
    return commands, hardware, warnings


def test_a_valid_message_sets_every_target_with_its_age_and_is_counted():
    commands, hardware, warnings = make()
    commands(velocity({'fl': 1.0, 'fr': -1.0}, stamp_ns=NOW_NS - 20_000_000))
    assert hardware.targets == [
        ('fl', JointTarget(Mode.VELOCITY, velocity=1.0), 20_000_000),
        ('fr', JointTarget(Mode.VELOCITY, velocity=-1.0), 20_000_000),
    ]
    stats = commands.stats()
    assert (stats.accepted, stats.rejected, stats.last_rejection) == (1, {}, None)
    assert warnings == []


def test_a_refused_message_sets_nothing_and_says_why_with_its_count():
    commands, hardware, warnings = make()
    bad = velocity({'fl': 1.0, 'rear': 1.0})
    commands(bad)
    commands(bad)
    assert hardware.targets == []
    stats = commands.stats()
    assert stats.accepted == 0 and stats.rejected == {'unknown_joint': 2}
    assert stats.last_rejection.startswith('unknown_joint: ')
    assert warnings[-1].startswith('rejected /actuator_cmd (unknown_joint, 2 so far): ')


def test_targets_from_states_before_the_first_published_are_refused():
    commands, hardware, _ = make()
    first = NOW_NS - 1_000_000_000
    commands(velocity({'fl': 1.0}, states_ns=first))  # refused: no states out yet
    commands.states_published(first)
    commands.states_published(first + 5_000_000)  # later states: still counted from the first
    commands(velocity({'fl': 1.0}, states_ns=first - 5_000_000))  # refused: another bridge's
    commands(velocity({'fl': 2.0}, states_ns=first))
    commands(velocity({'fl': 3.0}))  # not computed from states
    assert commands.stats().rejected == {'old_states': 2}
    assert [t.velocity for _, t, _ in hardware.targets] == [2.0, 3.0]
