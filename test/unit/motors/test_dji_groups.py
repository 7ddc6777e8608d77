"""DJI command groups: one shared frame per tick, built from the motors' raw targets."""

import pytest
from rm_base.hardware.errors import HardwareConfigError
from rm_base.motors import actuator_class
from rm_base.motors.dji.groups import DjiCommandGroup, build_dji_groups
from support.hardware import joint


def motor(name, type_, id_, bus='can0'):
    cfg = joint(name=name, type=type_, id=id_, bus=bus)
    return actuator_class(type_)(cfg)


def test_group_packs_the_members_raw_targets_into_one_frame():
    a, b, c = motor('a', 'm3508', 1), motor('b', 'm3508', 2), motor('c', 'm2006', 4)
    (group,) = build_dji_groups([a, b, c])
    a.command_raw, b.command_raw, c.command_raw = 1000, -1000, 2500
    msg = group.pack_command()
    assert msg.arbitration_id == 0x200
    assert not msg.is_extended_id
    # slot 3 (id 3) is empty -> 0
    assert bytes(msg.data) == bytes.fromhex('03 E8 FC 18 00 00 09 C4')


def test_groups_are_split_by_frame_and_bus():
    motors = [
        motor('w1', 'm3508', 1),
        motor('w5', 'm3508', 5),
        motor('yaw', 'gm6020', 2),  # 0x1FF slot 1, shared with C620 ids 5-8
        motor('pitch', 'gm6020', 5),  # 0x2FF
        motor('trig', 'gm6020_current', 3),  # 0x1FE
        motor('w1b', 'm3508', 1, bus='can1'),
    ]
    groups = {g.name: g for g in build_dji_groups(motors)}
    assert set(groups) == {'can0/0x200', 'can0/0x1FF', 'can0/0x2FF', 'can0/0x1FE', 'can1/0x200'}
    assert [m and m.name for m in groups['can0/0x1FF'].members] == ['w5', 'yaw', None, None]


def test_gm6020_and_c620_collision_is_a_config_error():
    with pytest.raises(HardwareConfigError, match='bus can0: yaw and w5 share command frame'):
        build_dji_groups([motor('w5', 'm3508', 5), motor('yaw', 'gm6020', 1)])


def test_the_same_id_on_two_buses_is_fine():
    assert len(build_dji_groups([motor('a', 'm3508', 1), motor('b', 'm3508', 1, 'can1')])) == 2


def test_group_refuses_foreign_members_and_ids():
    group = DjiCommandGroup('can0', 0x200)
    with pytest.raises(HardwareConfigError, match='does not belong'):
        group.add(motor('w5', 'm3508', 5))
    group.add(motor('a', 'm3508', 1))
    with pytest.raises(HardwareConfigError, match='share frame 0x200 slot 0'):
        group.add(motor('b', 'm2006', 1))
    with pytest.raises(HardwareConfigError, match='not a DJI command frame id'):
        DjiCommandGroup('can0', 0x201)
