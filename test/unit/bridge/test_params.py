"""Bridge parameters -> hardware config dict and simulator settings (no ROS needed)."""

import array

import pytest
from rm_base.bridge.errors import BridgeConfigError
from rm_base.bridge.params import (
    bus_log_path,
    is_ros_own,
    nest,
    settings_from_parameters,
    with_sim_world,
)
from rm_base.hardware import HardwareConfigError
from rm_base.runtime import realtime
from rm_base.sim import Timing

YAW = {
    'buses.can0.interface': 'socketcan',
    'joints.yaw.type': 'gm6020',
    'joints.yaw.bus': 'can0',
    'joints.yaw.id': 1,
}


def test_nest_turns_dotted_names_into_groups():
    assert nest({'a.b.c': 1, 'a.d': 2, 'e': 3}) == {'a': {'b': {'c': 1}, 'd': 2}, 'e': 3}


def test_when_a_name_has_a_value_and_keys_below_expect_error_naming_both():
    with pytest.raises(BridgeConfigError, match=r"'joints\.yaw\.id' is below 'joints\.yaw'"):
        nest({'joints.yaw': 3, 'joints.yaw.id': 1})


def test_when_a_name_part_is_empty_expect_error():
    with pytest.raises(BridgeConfigError, match='empty name part'):
        nest({'joints..id': 1})


def test_nest_turns_arrays_into_lists():
    assert nest({'a': array.array('d', [1.0, 2.0]), 'b': (1, 2)}) == {'a': [1.0, 2.0], 'b': [1, 2]}


def test_hardware_keys_reach_the_hardware_schema():
    params = {**YAML_PID, **YAW}
    settings = settings_from_parameters({'safety.command_timeout_s': 0.25}, params)
    (joint,) = settings.hardware_config.joints
    assert joint.name == 'yaw' and joint.type == 'gm6020' and joint.id == 1
    # an int from YAML is a valid gain
    assert joint.velocity_pid.kp == 1.0 and joint.velocity_pid.integral_separation == 2.0
    assert settings.hardware_config.safety.command_timeout_s == 0.25
    assert settings.hardware_config.rate_hz == 1000.0
    assert settings.sim is None


YAML_PID = {'joints.yaw.velocity_pid.kp': 1, 'joints.yaw.velocity_pid.integral_separation': 2.0}


def test_typed_settings_are_taken_over():
    typed = {'publish_rate': 100.0, 'diagnostics_rate': 2.0, 'publish_frames': True}
    settings = settings_from_parameters({**typed, 'scheduler.rate_hz': 500.0}, YAW)
    assert settings.publish_rate_hz == 100.0
    assert settings.diagnostics_rate_hz == 2.0
    assert settings.publish_frames is True
    assert settings.hardware_config.rate_hz == 500.0
    assert settings.hardware_config.priority == 50  # the bridge asks for SCHED_FIFO 50


def test_the_loop_priority_reaches_the_hardware_config_and_is_checked():
    settings = settings_from_parameters({'scheduler.priority': 0}, YAW)
    assert settings.hardware_config.priority == 0
    with pytest.raises(HardwareConfigError, match=r'scheduler\.priority must be <= 99, got 100'):
        settings_from_parameters({'scheduler.priority': 100}, YAW)


def test_the_loop_collects_garbage_unless_told_not_to():
    assert settings_from_parameters({}, YAW).hardware_config.collect_garbage is True
    settings = settings_from_parameters({'scheduler.collect_garbage': False}, YAW)
    assert settings.hardware_config.collect_garbage is False
    with pytest.raises(HardwareConfigError, match=r'scheduler\.collect_garbage'):
        settings_from_parameters({'scheduler.collect_garbage': 'no'}, YAW)


def test_the_process_runs_on_the_last_cpu_unless_told_which_or_none(monkeypatch):
    monkeypatch.setattr(realtime.os, 'sched_getaffinity', lambda pid: {0, 1})
    assert settings_from_parameters({}, YAW).cpu_index == -1
    assert settings_from_parameters({'scheduler.cpu': 0}, YAW).cpu_index == 0
    settings = settings_from_parameters({'scheduler.one_cpu': False, 'scheduler.cpu': 9}, YAW)
    assert settings.cpu_index is None  # not pinned: the index is not used, nor checked
    with pytest.raises(BridgeConfigError, match=r'scheduler\.cpu: CPU index 2 is outside'):
        settings_from_parameters({'scheduler.cpu': 2}, YAW)


def test_idle_cpus_are_asked_to_poll_unless_told_a_latency_or_nothing():
    assert settings_from_parameters({}, YAW).cpu_latency_us == 0
    assert settings_from_parameters({'scheduler.cpu_latency_us': 20}, YAW).cpu_latency_us == 20
    assert settings_from_parameters({'scheduler.cpu_latency_us': -1}, YAW).cpu_latency_us is None


def test_when_a_hardware_key_is_missing_expect_the_hardware_error_naming_it():
    params = {k: v for k, v in YAW.items() if k != 'joints.yaw.bus'}
    with pytest.raises(HardwareConfigError, match=r'joints\.yaw\.bus is required'):
        settings_from_parameters({}, params)


def test_when_a_parameter_is_unknown_expect_error_naming_it():
    with pytest.raises(BridgeConfigError, match="unknown parameter 'publish_rat'"):
        settings_from_parameters({}, {**YAW, 'publish_rat': 100.0})


def test_ros_own_parameters_are_recognised():
    assert is_ros_own('use_sim_time')
    assert is_ros_own('qos_overrides./actuator_cmd.subscription.depth')
    assert not is_ros_own('joints.yaw.id')


def test_when_sim_expect_every_bus_on_rm_sim_even_without_an_interface():
    params = {
        'buses.can0.interface': 'socketcan',
        'buses.can1.bitrate': 1_000_000,  # no interface at all
        'joints.yaw.type': 'gm6020',
        'joints.yaw.bus': 'can1',
        'joints.yaw.id': 1,
    }
    settings = settings_from_parameters({'sim': True}, params)
    assert {b.interface for b in settings.hardware_config.buses} == {'rm_sim'}
    assert settings.sim is not None and settings.sim.timing is Timing.REALTIME


def test_sim_can_puts_every_bus_and_the_motors_on_that_interface_channels_kept():
    params = {**YAW, 'buses.can0.channel': 'vcan7', 'buses.can0.interface': 'slcan'}
    settings = settings_from_parameters({'sim': True, 'sim.can': 'socketcan'}, params)
    bus = settings.hardware_config.buses[0]
    assert (bus.interface, bus.channel) == ('socketcan', 'vcan7')
    assert settings.sim is not None and settings.sim.can == 'socketcan'
    # with_sim_world leaves it alone: the world reaches it over the kernel, not in-process
    config = with_sim_world(settings.hardware, object())
    assert 'world' not in config['buses']['can0'].get('options', {})
    assert settings_from_parameters({'sim': True}, params).sim.can == 'rm_sim'


def test_sim_settings_come_from_sim_groups_and_joint_sim_keys():
    params = {
        **YAW,
        'joints.yaw.sim.load_inertia': 0.01,
        'joints.yaw.sim.limits.p_max': 12.5,
        'sim.body.gimbal.yaw.motor': 'yaw',
        'sim.imu.path': '/tmp/imu',
        'sim.imu.rate_hz': 200.0,
    }
    settings = settings_from_parameters(
        {'sim': True, 'sim.timing': 'stepped', 'sim.seed': 4}, params
    )
    sim = settings.sim
    assert sim.timing is Timing.STEPPED and sim.seed == 4
    assert sim.motors == {'yaw': {'load_inertia': 0.01, 'limits': {'p_max': 12.5}}}
    assert sim.body == {'gimbal': {'yaw': {'motor': 'yaw'}}}
    assert sim.imu == {'path': '/tmp/imu', 'rate_hz': 200.0}
    # the simulator's keys never reach the hardware schema (it would refuse them)
    assert 'sim' not in settings.hardware['joints']['yaw']


def test_when_not_sim_expect_sim_groups_ignored():
    params = {**YAW, 'joints.yaw.sim.load_inertia': 0.01, 'sim.body.gimbal.yaw.motor': 'yaw'}
    settings = settings_from_parameters({'sim': False}, params)
    assert settings.sim is None
    assert settings.hardware_config.buses[0].interface == 'socketcan'


def test_when_joint_sim_is_a_value_expect_error():
    with pytest.raises(BridgeConfigError, match=r"'joints\.yaw\.sim' must be a group"):
        settings_from_parameters({'sim': True}, {**YAW, 'joints.yaw.sim': True})


def test_when_sim_keys_name_an_unconfigured_joint_expect_error():
    params = {**YAW, 'joints.pitch.sim.load_inertia': 0.01}
    with pytest.raises(BridgeConfigError, match=r'joints\.pitch is not a configured joint'):
        settings_from_parameters({'sim': True}, params)


def test_log_file_of_a_single_bus_is_the_path_itself():
    settings = settings_from_parameters({'log_file': '/tmp/frames.asc'}, YAW)
    assert settings.hardware_config.buses[0].log_file == '/tmp/frames.asc'


def test_log_file_with_several_buses_gets_the_bus_name_and_a_bus_may_keep_its_own():
    params = {
        **YAW,
        'buses.can1.interface': 'socketcan',
        'buses.can2.interface': 'socketcan',
        'buses.can2.log_file': '/tmp/mine.log',
    }
    settings = settings_from_parameters({'log_file': '/tmp/frames.asc'}, params)
    logs = {b.name: b.log_file for b in settings.hardware_config.buses}
    assert logs == {
        'can0': '/tmp/frames_can0.asc',
        'can1': '/tmp/frames_can1.asc',
        'can2': '/tmp/mine.log',
    }


def test_bus_log_path():
    assert bus_log_path('/a/b.log', 'can0', False) == '/a/b.log'
    assert bus_log_path('/a/b.log', 'can0', True) == '/a/b_can0.log'


def test_with_sim_world_puts_the_world_object_in_every_bus_and_keeps_other_options():
    params = {**YAW, 'buses.can0.options.receive_own_messages': False}
    settings = settings_from_parameters({'sim': True}, params)
    world = object()
    config = with_sim_world(settings.hardware, world)
    assert config['buses']['can0']['options'] == {'receive_own_messages': False, 'world': world}
    # the settings themselves are not changed
    assert 'world' not in settings.hardware['buses']['can0']['options']
