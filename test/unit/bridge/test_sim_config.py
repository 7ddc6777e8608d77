"""The simulated world of a sim-mode bridge, from its hardware config and sim settings."""

import pytest
from rm_base.bridge.errors import BridgeConfigError
from rm_base.bridge.params import SimSettings
from rm_base.bridge.sim_config import motor_config, world_config
from rm_base.hardware import HardwareConfig
from rm_base.hardware.config import JointConfig
from rm_base.sim import SimWorld, Timing

from .helpers import unique_name


def joint(type_, id_=1, **extra):
    return JointConfig.from_dict('j', {'type': type_, 'bus': 'can0', 'id': id_, **extra})


@pytest.mark.parametrize(
    ('hardware_type', 'expected'),
    [
        ('m3508', {'type': 'm3508'}),
        ('m2006', {'type': 'm2006'}),
        ('gm6020', {'type': 'gm6020', 'control': 'voltage'}),
        ('gm6020_current', {'type': 'gm6020', 'control': 'current'}),
        ('dm4310', {'type': 'dm4310'}),
        ('dm4340', {'type': 'dm4310', 'model': 'DM4340'}),
        ('dm8009', {'type': 'dm8009'}),
        ('dm10010l', {'type': 'dm8009', 'model': 'DM10010L'}),
        ('cheetah', {'type': 'cheetah'}),
    ],
)
def test_motor_type_follows_the_joint_type(hardware_type, expected):
    assert motor_config(joint(hardware_type)) == {'id': 1, 'name': 'j', **expected}


def test_a_generic_damiao_is_simulated_by_its_size_class_with_its_model():
    assert motor_config(joint('damiao', model='DM8009'))['type'] == 'dm8009'
    config = motor_config(joint('damiao', model='DM4340'))
    assert config['type'] == 'dm4310' and config['model'] == 'DM4340'


def test_protocol_options_are_shared_with_the_simulated_device():
    config = motor_config(joint('dm4310', 3, master_id=0x30, limits={'p_max': 3.0}))
    assert config['master_id'] == 0x30 and config['limits'] == {'p_max': 3.0}
    dji = motor_config(joint('gm6020_current', si_per_raw=1.62 / 16384))
    assert dji['si_per_raw'] == 1.62 / 16384


def test_an_explicit_gear_ratio_keeps_the_rotor_and_rescales_the_output_constants():
    # An M3508 without its 3591/187 gearbox (friction wheel): k = 1 / 19.2032
    config = motor_config(joint('m3508', gear_ratio=1.0, torque_constant=0.0156))
    k = 187.0 / 3591.0
    assert config['gear_ratio'] == 1.0
    assert config['torque_constant'] == pytest.approx(0.3 * k)  # 0.0156 N·m/A
    assert config['back_emf_constant'] == pytest.approx(0.45 * k)
    assert config['coulomb_friction'] == pytest.approx(0.1 * k)
    assert config['viscous_friction'] == pytest.approx(2.5e-3 * k * k)
    # the same rotor: the no-load speed at 24 V scales with 1/k (~53 -> ~1024 rad/s)
    with SimWorld.from_config({'timing': 'stepped', 'channels': {unique_name(): [config]}}) as w:
        params = w.motor('j').model.params
        assert 24.0 / params.back_emf_constant == pytest.approx(24.0 / 0.45 / k)
        assert params.inertia == pytest.approx(1.2e-5)  # rotor side, unchanged


def test_joint_sim_overrides_win_over_the_rescaled_constants():
    config = motor_config(joint('m3508', gear_ratio=1.0), {'coulomb_friction': 0.0})
    assert config['coulomb_friction'] == 0.0


def test_joint_sim_overrides_win():
    config = motor_config(joint('m3508'), {'load_inertia': 0.01, 'overtemp_c': 100.0})
    assert config['load_inertia'] == 0.01 and config['overtemp_c'] == 100.0


def test_when_a_type_has_no_simulated_model_expect_error_naming_the_joint():
    with pytest.raises(BridgeConfigError, match=r"joints\.j\.type 'piper' has no simulated"):
        motor_config(joint('piper', 1))


def test_when_a_type_is_unknown_expect_the_hardware_message_not_the_simulators():
    with pytest.raises(BridgeConfigError, match=r"joints\.j\.type 'm3509' is unknown; known: "):
        motor_config(joint('m3509'))


def test_when_a_sim_type_override_is_no_simulated_motor_expect_error_naming_it():
    with pytest.raises(BridgeConfigError, match=r"joints\.j\.sim\.type 'm3590' is not a simulated"):
        motor_config(joint('m3508'), {'type': 'm3590'})


def hardware(**buses):
    joints = {}
    for bus, motors in buses.items():
        for name, type_, id_ in motors:
            joints[name] = {'type': type_, 'bus': bus, 'id': id_}
    channels = {bus: {'interface': 'rm_sim', 'channel': unique_name()} for bus in buses}
    return HardwareConfig.from_dict({'buses': channels, 'joints': joints})


def test_world_config_builds_one_world_with_a_channel_per_bus_body_and_imu(tmp_path, monkeypatch):
    monkeypatch.setenv('RM_TEST_IMU_DIR', str(tmp_path))
    hw = hardware(
        can0=[('fl', 'm3508', 1), ('fr', 'm3508', 2), ('rl', 'm3508', 3), ('rr', 'm3508', 4)],
        can1=[('yaw', 'gm6020', 1), ('pitch', 'dm4310', 2)],
    )
    sim = SimSettings(
        timing=Timing.STEPPED,
        body={
            'chassis': {
                'type': 'mecanum',
                'motors': ['fl', 'fr', 'rl', 'rr'],
                'wheelbase': 0.4,
                'track': 0.4,
                'wheel_radius': 0.076,
            },
            'gimbal': {'yaw': {'motor': 'yaw'}, 'pitch': {'motor': 'pitch'}},
        },
        imu={'path': '${RM_TEST_IMU_DIR}/imu', 'mount': 'gimbal'},
        motors={'yaw': {'load_inertia': 0.01}},
    )
    config = world_config(hw, sim)
    channel0, channel1 = (str(b.channel) for b in hw.buses)
    assert [m['name'] for m in config['channels'][channel0]] == ['fl', 'fr', 'rl', 'rr']
    assert config['channels'][channel1][0]['load_inertia'] == 0.01
    with SimWorld.from_config(config) as world:
        assert world.timing is Timing.STEPPED
        assert world.body.yaw_joint.device is world.motor('yaw')
        assert len(world.body.wheels) == 4
        assert world.imu().path == str(tmp_path / 'imu')
        world.step(2)


def test_when_two_buses_share_a_channel_expect_error():
    hw = HardwareConfig.from_dict(
        {
            'buses': {
                'can0': {'interface': 'rm_sim', 'channel': 'x'},
                'can1': {'interface': 'rm_sim', 'channel': 'x'},
            },
            'joints': {'a': {'type': 'm3508', 'bus': 'can0', 'id': 1}},
        }
    )
    with pytest.raises(BridgeConfigError, match="both 'x'"):
        world_config(hw, SimSettings())


def test_a_supercap_is_simulated_on_its_bus_channel_with_the_sim_keys():
    hardware = HardwareConfig.from_dict({
        'buses': {'can0': {'interface': 'virtual', 'channel': 'chassis_bus'}},
        'joints': {'w': {'type': 'm3508', 'bus': 'can0', 'id': 1}},
        'supercap': {'bus': 'can0'},
    })
    config = world_config(hardware, SimSettings(supercap={'capacity_j': 500.0}))
    assert config['supercap'] == {'capacity_j': 500.0, 'channel': 'chassis_bus'}
    assert world_config(hardware, SimSettings())['supercap'] == {'channel': 'chassis_bus'}
    with pytest.raises(BridgeConfigError, match=r'the board is on supercap\.bus'):
        world_config(hardware, SimSettings(supercap={'channel': 'other'}))
    plain = HardwareConfig.from_dict({
        'buses': {'can0': {'interface': 'virtual'}},
        'joints': {'w': {'type': 'm3508', 'bus': 'can0', 'id': 1}},
    })
    with pytest.raises(BridgeConfigError, match=r'sim\.supercap\.\* is set, but there is no'):
        world_config(plain, SimSettings(supercap={'capacity_j': 500.0}))
