"""bag plot: data found by type, PNGs written, missing parts skipped, nothing -> error."""

import matplotlib.image
import numpy as np
import pytest
from rm_bringup.cli.bag_plot import modes_seen, read_plot_data
from rm_bringup.cli.main import main
from support.old_bags import older_store, write_old_bag

S = 1_000_000_000
T0 = 100 * S  # bag start [ns]


@pytest.fixture
def robot_bag(write_bag, make):
    """Every plottable type, on topic names other than the defaults where names are free."""
    twist, vec = 'geometry_msgs/msg/Twist', 'geometry_msgs/msg/Vector3'
    samples = []
    for i in range(20):
        t = T0 + i * S // 10  # 10 Hz for 1.9 s
        command = make(twist, linear=make(vec, x=0.1 * i, y=-0.05 * i), angular=make(vec, z=0.2))
        samples.append(('/vel_cmd', twist, t, command))
        measured = make(twist, linear=make(vec, x=0.09 * i), angular=make(vec, z=0.18))
        samples.append(
            (
                '/robot/chassis_state',
                'rm_msgs/msg/ChassisState',
                t + 5_000_000,
                make(
                    'rm_msgs/msg/ChassisState',
                    state=4 if i >= 10 else 1,
                    cmd_vel=command,
                    measured_vel=measured,
                ),
            )
        )
        samples.append(
            (
                '/robot/gimbal_state',
                'rm_msgs/msg/GimbalState',
                t + 7_000_000,
                make(
                    'rm_msgs/msg/GimbalState',
                    state=1,
                    yaw=0.01 * i,
                    yaw_target=0.2,
                    pitch=-0.01 * i,
                    pitch_target=-0.1,
                ),
            )
        )
        samples.append(
            (
                '/robot/shooter_state',
                'rm_msgs/msg/ShooterState',
                t + 9_000_000,
                make(
                    'rm_msgs/msg/ShooterState',
                    state=3 if 5 <= i < 12 else 2,
                    shots_fired=max(0, i - 5),
                    burst_remaining=max(0, 12 - i),
                ),
            )
        )
    samples.append(
        ('/chassis_cmd', 'rm_msgs/msg/ChassisCmd', T0 + S, make('rm_msgs/msg/ChassisCmd', mode=4))
    )
    samples.append(
        (
            '/shoot_cmd',
            'rm_msgs/msg/ShootCmd',
            T0 + S // 2,
            make('rm_msgs/msg/ShootCmd', mode=2, num=7),
        )
    )
    samples.append(
        ('/chatter', 'std_msgs/msg/String', T0 + S, make('std_msgs/msg/String', data='ignored'))
    )
    odom_twist = make('geometry_msgs/msg/TwistWithCovariance', twist=measured)
    samples.append(
        (
            '/odom',
            'nav_msgs/msg/Odometry',
            T0 + 3 * S // 2,
            make('nav_msgs/msg/Odometry', twist=odom_twist),
        )
    )
    return write_bag(samples)


def test_state_topics_are_found_by_type_not_by_name(robot_bag):
    data = read_plot_data(robot_bag)
    topics = {(t.topic, t.msgtype) for t in data.tracks}
    assert ('/robot/chassis_state', 'rm_msgs/msg/ChassisState') in topics
    assert ('/robot/gimbal_state', 'rm_msgs/msg/GimbalState') in topics
    assert ('/robot/shooter_state', 'rm_msgs/msg/ShooterState') in topics
    assert '/chatter' not in {t.topic for t in data.tracks}


def test_values_and_times_are_read_from_the_messages(robot_bag):
    data = read_plot_data(robot_bag)
    (command,) = data.of_type('geometry_msgs/msg/Twist')
    assert command.t[:3] == pytest.approx([0.0, 0.1, 0.2])  # 10 Hz from the bag start
    assert command.columns['vx'][3] == pytest.approx(0.3)  # 0.1 * i at i = 3
    (state,) = data.of_type('rm_msgs/msg/ChassisState')
    assert state.t[0] == pytest.approx(0.005)
    assert state.columns['measured_vx'][10] == pytest.approx(0.9)  # 0.09 * 10
    assert state.columns['cmd_wz'][0] == pytest.approx(0.2)
    assert state.columns['state'][9:11] == [1.0, 4.0]
    (shooter,) = data.of_type('rm_msgs/msg/ShooterState')
    assert shooter.columns['shots_fired'][-1] == 14  # max(0, 19 - 5)
    (odom,) = data.of_type('nav_msgs/msg/Odometry')
    assert odom.columns['wz'] == [pytest.approx(0.18)]
    modes = data.state_names['rm_msgs/msg/ChassisCmd']
    assert [modes[v] for v in range(6)] == ['PASSIVE', 'RAW', 'FOLLOW', 'TWIST', 'GYRO',
                                            'POSITION']  # not the speed gears' names
    assert data.state_names['rm_msgs/msg/ShooterState'][3] == 'PUSH'


def test_the_modes_a_bag_went_through_are_said_by_name(robot_bag):
    said = {line.split(':')[0]: line.split(': ')[1] for line in modes_seen(
        read_plot_data(robot_bag))}
    assert said['/robot/chassis_state state'] == 'RAW, GYRO'  # states 1 then 4


def assert_real_png(path, min_bytes=15_000):
    assert path.is_file(), path
    assert path.stat().st_size > min_bytes, f'{path} is only {path.stat().st_size} bytes'
    gray = (matplotlib.image.imread(path)[..., :3].mean(axis=-1) * 255).astype(np.uint8)
    # A blank figure is one colour; lines, text and antialiasing make many grey levels,
    # and axes with data ink a few percent of the (white) canvas.
    assert len(np.unique(gray)) > 50
    assert (gray < 200).mean() > 0.01


def test_plot_writes_the_three_pngs(robot_bag, tmp_path, capsys):
    out = tmp_path / 'plots'
    assert main(['bag', 'plot', str(robot_bag), '-o', str(out)]) == 0
    for name in ('chassis_velocity.png', 'gimbal.png', 'shooter.png'):
        assert_real_png(out / name)
    assert 'skipped' not in capsys.readouterr().out


def test_missing_parts_are_skipped_with_a_note(write_bag, make, tmp_path, capsys):
    bag = write_bag(
        [
            (
                '/g',
                'rm_msgs/msg/GimbalState',
                T0 + i * S // 10,
                make('rm_msgs/msg/GimbalState', yaw=0.1 * i),
            )
            for i in range(10)
        ]
    )
    out = tmp_path / 'plots'
    assert main(['bag', 'plot', str(bag), '-o', str(out)]) == 0
    assert_real_png(out / 'gimbal.png')
    assert not (out / 'chassis_velocity.png').exists()
    printed = capsys.readouterr().out
    assert 'skipped chassis_velocity.png' in printed and 'skipped shooter.png' in printed


def test_twist_on_another_topic_is_not_a_velocity_command(write_bag, make):
    twist = make('geometry_msgs/msg/Twist')
    bag = write_bag([('/cmd_vel_unrelated', 'geometry_msgs/msg/Twist', T0, twist)])
    assert read_plot_data(bag).tracks == []


def test_nothing_plottable_is_one_clear_error(write_bag, make, tmp_path, capsys):
    bag = write_bag(
        [('/chatter', 'std_msgs/msg/String', T0, make('std_msgs/msg/String', data='x'))]
    )
    assert main(['bag', 'plot', str(bag), '-o', str(tmp_path / 'plots')]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith('rmcli: error: nothing to plot in') and 'GimbalState' in err
    assert '\n' not in err


def test_a_topic_recorded_with_a_string_mode_is_skipped_with_a_line_not_a_crash(
    write_bag, make, tmp_path, capsys
):
    # The finding: `bag plot` raised ValueError on a bag whose ChassisCmd.mode was recorded
    # as a string (which `bag play` refuses cleanly).
    store = older_store(lambda t: t.replace('uint8 mode', 'string mode'))
    old = write_old_bag(tmp_path / 'old', store, mode='GYRO')
    data = read_plot_data(old)
    assert data.tracks == []
    assert "its mode is str 'GYRO', not a number" in data.skipped['/chassis_cmd']
    assert main(['bag', 'plot', str(old), '-o', str(tmp_path / 'plots')]) == 1
    err = capsys.readouterr().err
    assert 'skipped /chassis_cmd: its mode is str' in err and 'Traceback' not in err
