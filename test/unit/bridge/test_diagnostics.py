"""The bridge's DiagnosticArray: levels, messages and values."""

import dataclasses
import math

import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from rm_base.bridge.diagnostics import CommandStats, DiagnosticsReporter, SimulatorStats
from rm_base.bridge.messages import time_msg
from rm_base.hardware import BusStats, JointState
from rm_base.hardware.can_link import LinkReport
from rm_base.loop import PeriodStats

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def joint_diag(hold):
    return {
        'type': 'm3508',
        'bus': 'can0',
        'hold_reason': hold,
        'frames_decoded': 10,
        'decode_errors': 0,
        'commands_accepted': 3,
        'commands_rejected': 1,
        'last_rejection': 'velocity is nan',
        'update_errors': 0,
    }


def bus_stats(state='up', load=0.3, **changes):
    values = dict(
        name='can0',
        state=state,
        frames_sent=100,
        frames_received=90,
        frames_unmatched=0,
        send_errors=0,
        receive_errors=0,
        error_frames=0,
        handler_errors=0,
        reopen_count=1,
        open_failures=0,
        generation=2,
        load_bps=load * 1e6,
        load_fraction=load,
        last_error='send failed: bus-off',
    )
    values.update(changes)
    return BusStats(**values)


def scheduler_stats(overruns=0, errors=0):
    return PeriodStats(1_000_000, 5000, overruns, overruns, 800.0, 60.0, (1,) * 9, 300.0, errors)


def build(reporter, hold='none', online=True, bus=None, scheduler=None, commands=None,
          link=None):
    state = JointState(
        'wheel',
        1.0,
        2.0,
        0.1,
        40.0 if online else math.nan,
        online,
        0,
        2 if hold == 'none' else 0,
        0.2 if hold == 'none' else 0.0,
    )
    hardware = {
        'joints': {'wheel': joint_diag(hold)},
        'buses': {'can0': bus or bus_stats()},
        'scheduler': scheduler or scheduler_stats(),
        'links': {'can0': link} if link is not None else {},
    }
    msg = reporter.build(hardware, [state], commands or CommandStats(), time_msg(0))
    return {s.name: s for s in msg.status}


def values(status):
    return {kv.key: kv.value for kv in status.values}


@pytest.mark.parametrize(
    ('hold', 'level', 'message'),
    [
        ('none', OK, 'driven (VELOCITY)'),
        ('no_command', OK, 'idle: no command yet'),
        ('off', OK, 'off (commanded)'),
        ('command_timeout', WARN, 'held at zero: command_timeout'),
        ('bus_recovery', WARN, 'held at zero: bus_recovery'),
        ('offline', ERROR, 'held at zero: offline'),
        ('over_temperature', ERROR, 'held at zero: over_temperature'),
        ('device_fault', ERROR, 'held at zero: device_fault'),
        ('error', ERROR, 'held at zero: error'),
    ],
)
def test_joint_level_and_message_follow_the_hold_reason(hold, level, message):
    status = build(DiagnosticsReporter('can_bridge'), hold)['can_bridge: joint wheel']
    assert (status.level, status.message) == (level, message)
    assert values(status)['hold_reason'] == hold


def test_joint_values_and_hardware_id():
    reporter = DiagnosticsReporter('can_bridge', {'wheel': 'can0 m3508 id 1'})
    status = build(reporter)['can_bridge: joint wheel']
    assert status.hardware_id == 'can0 m3508 id 1'
    v = values(status)
    assert v['online'] == 'True'
    assert v['temperature [degC]'] == '40'
    assert v['error_code'] == '0'
    assert v['mode'] == 'VELOCITY'
    assert v['command [N*m]'] == '0.2'
    assert v['last_rejection'] == 'velocity is nan'


def test_a_families_details_join_the_joints_values():
    diag = {**joint_diag('none'), 'details': {'torque_range [N*m]': 18.0}}
    reporter = DiagnosticsReporter('can_bridge')
    state = JointState('wheel', 0.0, 0.0, 0.0, math.nan, True, 0, 0, 0.0)
    msg = reporter.build({'joints': {'wheel': diag}, 'buses': {'can0': bus_stats()},
                          'scheduler': scheduler_stats()}, [state], CommandStats(), time_msg(0))
    assert values(msg.status[0])['torque_range [N*m]'] == '18'


def test_offline_joint_reports_nan_temperature():
    status = build(DiagnosticsReporter('b'), 'offline', online=False)['b: joint wheel']
    assert values(status)['online'] == 'False'
    assert values(status)['temperature [degC]'] == 'nan'


@pytest.mark.parametrize(
    ('bus', 'level', 'message'),
    [
        (bus_stats(), OK, 'up'),
        (bus_stats(load=0.9), WARN, 'up, load 90 %'),
        (bus_stats('down'), ERROR, 'down, reopening: send failed: bus-off'),
        (bus_stats('closed'), WARN, 'closed'),
    ],
)
def test_bus_level(bus, level, message):
    status = build(DiagnosticsReporter('b'), bus=bus)['b: bus can0']
    assert (status.level, status.message) == (level, message)
    v = values(status)
    assert v['reopen_count'] == '1'
    assert v['send_errors'] == '0'


@pytest.mark.parametrize(
    ('link', 'level', 'message'),
    [
        (LinkReport(exists=True, up=True, kind='can', can_state='ERROR-ACTIVE'), OK, 'up'),
        (LinkReport(exists=True, up=True, kind='can', can_state='ERROR-PASSIVE'), WARN,
         'controller ERROR-PASSIVE; up'),
        (LinkReport(exists=True, up=True, kind='can', can_state='BUS-OFF'), ERROR,
         'controller BUS-OFF; up'),
        (LinkReport(exists=True, up=False, kind='vcan'), ERROR, 'link down (kernel); up'),
        (LinkReport(exists=False), ERROR, 'the interface does not exist'),
    ],
)
def test_the_kernels_view_of_a_socketcan_bus_sets_its_level(link, level, message):
    status = build(DiagnosticsReporter('b'), bus=bus_stats(), link=link)['b: bus can0']
    assert (status.level, status.message) == (level, message)


def test_the_kernels_counters_and_the_last_error_frame_are_values():
    link = LinkReport(exists=True, up=True, kind='can', can_state='ERROR-WARNING',
                      tx_error_counter=97, rx_error_counter=2, restart_ms=100,
                      counters={'rx_dropped': 4, 'bus_off': 1})
    bus = bus_stats(error_frames=3, bus_off=1, last_error_frame='bus-off')
    v = values(build(DiagnosticsReporter('b'), bus=bus, link=link)['b: bus can0'])
    assert (v['kernel link'], v['kernel can_state'], v['kernel tx_error_counter'],
            v['kernel restart_ms'], v['kernel rx_dropped'], v['kernel bus_off']) == (
        'up', 'ERROR-WARNING', '97', '100', '4', '1')
    assert (v['error_frames'], v['bus_off'], v['last_error_frame']) == ('3', '1', 'bus-off')


def test_bus_without_bitrate_has_no_load_fraction():
    status = build(DiagnosticsReporter('b'), bus=bus_stats(load_fraction=None))['b: bus can0']
    assert values(status)['load [%]'] == 'unknown (no bitrate)'


def test_scheduler_warns_about_new_overruns_only_once():
    reporter = DiagnosticsReporter('b')
    first = build(reporter, scheduler=scheduler_stats(overruns=3))['b: scheduler']
    second = build(reporter, scheduler=scheduler_stats(overruns=3))['b: scheduler']
    assert (first.level, first.message) == (WARN, '3 overrun(s) since the last report')
    assert (second.level, second.message) == (OK, 'on time')
    v = values(second)
    assert v['rate [Hz]'] == '1000'
    assert v['period_error_max [us]'] == '800'
    assert v['period_error <10 [us]'] == '1'
    assert v['period_error >=5000 [us]'] == '1'


def test_the_loop_reports_its_lateness_and_every_component():
    from rm_base.loop import DurationSummary

    stats = dataclasses.replace(
        scheduler_stats(),
        lateness=DurationSummary(5000, 80.0, 450.0, 3000.0),
        components=(
            ('feedback', DurationSummary(5000, 30.0, 110.0, 900.0)),
            ('plugin chassis', DurationSummary(1000, 240.0, 520.0, 1500.0)),
        ),
    )
    v = values(build(DiagnosticsReporter('b'), scheduler=stats)['b: scheduler'])
    assert (v['lateness p50 [us]'], v['lateness p99 [us]']) == ('80', '450')
    assert (v['plugin chassis runs'], v['plugin chassis p99 [us]']) == ('1000', '520')
    assert v['feedback max [us]'] == '900'


def test_scheduler_errors_are_errors():
    status = build(DiagnosticsReporter('b'), scheduler=scheduler_stats(errors=1))['b: scheduler']
    assert status.level == ERROR


def test_commands_warn_about_new_rejections():
    reporter = DiagnosticsReporter('b')
    stats = CommandStats(10, {'non_finite': 2}, 'non_finite: fl: velocity is nan')
    first = build(reporter, commands=stats)['b: commands']
    second = build(reporter, commands=stats)['b: commands']
    assert first.level == WARN and second.level == OK
    v = values(first)
    assert v['accepted'] == '10'
    assert v['rejected'] == '2'
    assert v['rejected non_finite'] == '2'
    assert v['last_rejection'] == 'non_finite: fl: velocity is nan'


def test_the_supercap_is_a_status_of_its_own_and_warns_when_the_chassis_falls_back():
    from rm_base.hardware.supercap import CapState, PowerSupply, Supercap, SupercapConfig

    cap = Supercap(SupercapConfig(bus='can0'), 1000.0)
    state = JointState('wheel', 0.0, 0.0, 0.0, 40.0, True, 0, 0, 0.0)
    hardware = {'joints': {'wheel': joint_diag('none')}, 'buses': {'can0': bus_stats()},
                'scheduler': scheduler_stats(), 'supercap': cap.report(0)}
    reporter = DiagnosticsReporter('can_bridge')
    status = {s.name: s for s in reporter.build(hardware, [state], CommandStats(),
                                                time_msg(0)).status}['can_bridge: supercap']
    assert (status.level, status.message) == (
        WARN, 'offline; the chassis keeps to the referee limit')
    assert status.hardware_id == 'can0/supercap'
    assert values(status)['state'] == CapState.OFFLINE.value
    cap.allow(70.0, PowerSupply(referee_limit_w=80.0), 0)
    hardware['supercap'] = cap.report(0)
    status = {s.name: s for s in reporter.build(hardware, [state], CommandStats(),
                                                time_msg(0)).status}['can_bridge: supercap']
    assert values(status)['referee limit [W]'] == '80'


def simulator_status(reporter, slips, slipped_ns):
    msg = reporter.build({'joints': {}, 'buses': {}, 'scheduler': scheduler_stats()}, [],
                         CommandStats(), time_msg(0), SimulatorStats(2_500_000_000, slips,
                                                                     slipped_ns))
    return {s.name: s for s in msg.status}['b: simulator']


def test_a_simulator_that_slipped_warns_once_with_what_it_lost():
    reporter = DiagnosticsReporter('b')
    kept_up = simulator_status(reporter, 0, 0)
    assert (kept_up.level, kept_up.message) == (OK, 'keeping up with the wall clock')
    slipped = simulator_status(reporter, 2, 400_000_000)
    assert slipped.level == WARN
    assert slipped.message == ('simulated time slipped 2 time(s) since the last report (CPU '
                               'starved): it ran slower than the wall clock')
    assert {v.key: v.value for v in slipped.values} == {
        'time [s]': '2.5', 'slips': '2', 'slipped [s]': '0.4'}
    assert simulator_status(reporter, 2, 400_000_000).level == OK


def test_a_bridge_without_a_realtime_world_reports_no_simulator():
    reporter = DiagnosticsReporter('b')
    msg = reporter.build({'joints': {}, 'buses': {}, 'scheduler': scheduler_stats()}, [],
                         CommandStats(), time_msg(0))
    assert not [s for s in msg.status if s.name == 'b: simulator']
