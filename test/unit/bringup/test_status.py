"""The bringup status line, from the latest messages."""

import math

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rm_bringup.status import REFUSED_HOLD_S, StatusView, format_status

from rm_msgs.msg import ActuatorState, ChassisCmd, ChassisState, GimbalState, ShooterState


def _status(name, values):
    return DiagnosticStatus(
        name=name, values=[KeyValue(key=k, value=str(v)) for k, v in values.items()]
    )


def test_when_nothing_arrived_expect_waiting():
    assert format_status({'diagnostics': {}}) == 'waiting for the robot...'


def test_when_every_source_reports_expect_one_line_with_all_of_them():
    chassis = ChassisState(state=ChassisCmd.GYRO, wheel_speed=[19.1, -3.2, 3.25, -19.1])
    chassis.measured_vel.linear.x = 0.98
    chassis.measured_vel.angular.z = 5.97
    gimbal = GimbalState(state=1, yaw=0.123, pitch=-0.05)
    shooter = ShooterState(state=ShooterState.READY, shots_fired=5)
    actuators = ActuatorState(
        name=['wheel_fl', 'yaw'], online=[True, False], temperature=[75.0, math.nan]
    )
    diagnostics = {
        'can_bridge: bus can0': _status('can_bridge: bus can0', {'load [%]': 31.4}),
        'can_bridge: bus can1': _status('can_bridge: bus can1', {'load [%]': 18.0}),
        'can_bridge: scheduler': _status('can_bridge: scheduler', {'overruns': 2}),
    }
    line = format_status(
        {
            'chassis': chassis,
            'gimbal': gimbal,
            'shooter': shooter,
            'actuators': actuators,
            'diagnostics': diagnostics,
        }
    )
    assert line == (
        'chassis GYRO v(0.98,0.00,5.97) | wheels 19.1 -3.2 3.2 -19.1 | gimbal RATE y 0.12 '
        'p -0.05 | shooter READY 5 shots | can0 31% can1 18% | overruns 2 | offline yaw | '
        'hot wheel_fl 75C'
    )


def test_a_simulator_that_slipped_says_how_far_and_one_that_kept_up_nothing():
    def line(slipped):
        status = _status('can_bridge: simulator', {'slips': 3, 'slipped [s]': slipped})
        return format_status({'diagnostics': {status.name: status}})

    assert line(0.4173) == 'sim slipped 0.4 s'
    assert line('fast') == 'waiting for the robot...'  # not a number: nothing said
    assert line(0.0) == 'waiting for the robot...'  # nothing else said anything


def test_commands_refused_a_moment_ago_are_named():
    assert format_status({'refused': '/chassis_cmd,/vel_cmd', 'diagnostics': {}}) == \
        'refused chassis vel'
    assert format_status({'refused': '', 'diagnostics': {}}) == 'waiting for the robot...'


def test_the_view_holds_a_refusal_for_a_few_seconds_after_its_report():
    class Node:
        def create_subscription(self, *args):
            pass

    now = [100.0]
    view = StatusView(Node(), clock=lambda: now[0])

    def report(refused):
        msg = DiagnosticArray(status=[_status('rm_robot: commands', {
            'chassis /chassis_cmd rejected': 3, 'rejected since the last report': refused})])
        view._on_diagnostics(msg)

    report('/chassis_cmd')
    report('')  # the next report, a second later: nothing new, the refusal still shown
    now[0] += REFUSED_HOLD_S - 0.1
    assert view.line() == 'refused chassis'
    now[0] += 0.2
    assert view.line() == 'waiting for the robot...'


def test_when_a_shooter_faults_expect_fault_shown():
    line = format_status({'shooter': ShooterState(state=0, fault=True), 'diagnostics': {}})
    assert line == 'shooter PASSIVE 0 shots FAULT'


def test_when_one_source_commands_everything_expect_its_name():
    status = _status('rm_robot: command sources', {
        '/chassis_cmd in charge': 'manual', '/gimbal_cmd in charge': 'manual',
        '/chassis_cmd manual taken': 5})
    line = format_status({'diagnostics': {status.name: status}})
    assert line == 'cmd manual'


def test_when_sources_share_the_topics_expect_each_topics_source():
    status = _status('rm_robot: command sources', {
        '/chassis_cmd in charge': 'external', '/gimbal_cmd in charge': 'manual',
        '/shoot_cmd in charge': ''})
    line = format_status({'diagnostics': {status.name: status}})
    assert line == 'cmd chassis:external gimbal:manual shoot:-'


def test_when_the_chassis_moves_to_a_position_expect_its_name_not_a_number():
    line = format_status({'chassis': ChassisState(state=ChassisCmd.POSITION), 'diagnostics': {}})
    assert line.startswith('chassis POSITION ')


def test_a_narrow_terminal_drops_the_wheels_then_the_loads_before_cutting():
    # The finding: at 80 columns the line ended at `gimbal PASSI`.
    from rm_bringup.status import fit_status

    line = ('chassis GYRO v(0.61,-0.77,4.60) | wheels 19.1 -3.2 3.2 -19.1 | gimbal RATE y 0.12 '
            'p -0.05 | shooter READY 5 shots | can0 31% can1 18% | overruns 0/s | cmd external'
            ' | offline -')
    fitted = fit_status(line, 84)
    assert len(fitted) <= 84 and 'wheels' not in fitted
    assert 'gimbal RATE' in fitted and 'shooter READY 5 shots' in fitted
    assert fit_status(line, len(line)) == line
    assert fit_status(line, 30) == line[:29] + '>'


def test_overruns_are_a_rate_once_two_reports_came():
    line = format_status({'overrun_rate': 12.4, 'diagnostics': {
        'can_bridge: scheduler': _status('can_bridge: scheduler', {'overruns': 241558})}})
    assert line == 'overruns 12/s'


def test_the_pose_follows_the_chassis_and_the_referee_part_says_hp_and_cuts():
    from nav_msgs.msg import Odometry

    from rm_msgs.msg import RefereeRobotStatus

    odom = Odometry()
    odom.pose.pose.position.x, odom.pose.pose.position.y = 1.0, 0.5
    odom.pose.pose.orientation.z = math.sin(math.pi / 4)  # a quarter turn left
    odom.pose.pose.orientation.w = math.cos(math.pi / 4)
    alive = RefereeRobotStatus(hp=150, max_hp=200, gimbal_power=True, chassis_power=False,
                               shooter_power=True)
    line = format_status({'chassis': ChassisState(state=ChassisCmd.POSITION), 'odom': odom,
                          'referee': alive, 'diagnostics': {}})
    assert line == ('chassis POSITION v(0.00,0.00,0.00) | pose 1.00 0.50 90deg | '
                    'hp 150/200 power off chassis')
    dead = RefereeRobotStatus(hp=0, max_hp=200)
    assert format_status({'referee': dead, 'diagnostics': {}}) == 'hp 0/200 DESTROYED'
    whole = RefereeRobotStatus(hp=200, max_hp=200, gimbal_power=True, chassis_power=True,
                               shooter_power=True)
    assert format_status({'referee': whole, 'diagnostics': {}}) == 'hp 200/200'


def test_the_supercap_shows_how_full_it_is_and_what_it_does_or_that_it_is_offline():
    def line(values):
        status = _status('can_bridge: supercap', values)
        return format_status({'diagnostics': {status.name: status}})

    assert line({'state': 'burst', 'energy [%]': 73.4}) == 'cap 73% burst'
    assert line({'state': 'offline', 'energy [%]': math.nan}) == 'cap offline'
    assert line({'state': 'fault', 'energy [%]': 'unknown'}) == 'cap fault'
