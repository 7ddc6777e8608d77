"""bringup's command line: its own options, and ROS arguments a launcher appends left to rclpy."""

from rm_bringup.bringup import parse_args


def test_options_are_read():
    args = parse_args(['--config', '/tmp/my_robot.yaml', '--sim', '--no-status'])
    assert (args.config, args.sim, args.no_status, args.robot) == (
        '/tmp/my_robot.yaml', True, True, 'standard',
    )


def test_ros_arguments_appended_by_a_launcher_are_ignored():
    args = parse_args(['--robot', 'hero', '--ros-args', '-r', '__node:=bringup', '-p', 'a:=1'])
    assert args.robot == 'hero'
    assert not args.sim


def test_extra_parameter_files_are_kept_in_order():
    args = parse_args(['--sim', '--params-file', 'a.yaml', '--params-file', 'b.yaml'])
    assert [str(p) for p in args.params_file] == ['a.yaml', 'b.yaml']


def test_sim_can_names_rm_sims_interface_and_needs_sim(capsys):
    assert parse_args(['--sim', '--sim-can', 'socketcan']).sim_can == 'socketcan'
    assert parse_args(['--sim']).sim_can is None
    try:
        parse_args(['--sim-can', 'socketcan'])
    except SystemExit as err:
        assert err.code == 2
    else:
        raise AssertionError('--sim-can without --sim was taken')
    assert '--sim-can needs --sim' in capsys.readouterr().err
