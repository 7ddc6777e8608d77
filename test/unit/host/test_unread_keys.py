"""unread_keys: which keys of a host's files nothing read, and how that is said."""

import pytest
from rm_base.host.unread_keys import UnreadKeys, unknown_keys_error, unread_keys

DECLARED = {'plugins', 'state_period', 'shooter.type', 'shooter.rate', 'shooter.max_hz',
            'imu.type', 'imu.calibration.file'}


@pytest.mark.parametrize(
    ('given', 'plugins', 'expected'),
    [
        # everything given was read
        (DECLARED, ['shooter', 'imu'], UnreadKeys((), ())),
        # a typo of a loaded plugin's key, and of the node's own
        ({'shooter.max_hzz', 'state_perod'}, ['shooter'],
         UnreadKeys(('shooter.max_hzz', 'state_perod'), ())),
        # a key of the right plugin at the wrong depth (a block under the wrong plugin)
        ({'shooter.calibration.file'}, ['shooter', 'imu'],
         UnreadKeys(('shooter.calibration.file',), ())),
        # a plugin's config that the list leaves out: named, its keys not refused
        ({'ui.type', 'ui.rate', 'ui.aim.x', 'autoaim.type'}, ['shooter'],
         UnreadKeys((), ('autoaim', 'ui'))),
        # a group with no type is not a plugin's config: its keys are unknown
        ({'uii.rate'}, ['shooter'], UnreadKeys(('uii.rate',), ())),
        # 'x.type' deeper down does not make a plugin config
        ({'command_source.manual.type'}, ['shooter'],
         UnreadKeys(('command_source.manual.type',), ())),
    ],
)
def test_unread_keys_are_unknown_unless_a_plugin_not_loaded_holds_them(given, plugins, expected):
    assert unread_keys(given, DECLARED, plugins) == expected


def test_the_error_names_each_key_and_the_nearest_declared_name():
    message = unknown_keys_error('rm_robot', ['state_perod', 'shooter.max_hzz', 'zzz'], DECLARED)
    assert message.startswith(
        "rm_robot: unknown parameter(s) 'shooter.max_hzz' (did you mean 'shooter.max_hz'?), "
        "'state_perod' (did you mean 'state_period'?), 'zzz': "
    )
    assert '\n' not in message
