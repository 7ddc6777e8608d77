"""Broken files: bags for rmcli and config files for can_bridge, rm_robot and bringup.

Rule: a damaged input is one clear line (no traceback) and exit status 1, or it is read
fine; it never crashes the tool with an exception.

* Bags (hypothesis): MCAP and SQLite bags truncated anywhere, with bytes overwritten
  anywhere, and with a damaged metadata.yaml, through ``rmcli bag info`` and the
  ``rmcli bag play`` read loop (stand-in publishers, no ROS: the loop reads every message).
* Config files: a YAML syntax error, a missing key and a wrong type, for can_bridge and
  rm_robot (in-process: the node's ConfigError names the key) and as processes for the
  console scripts and bringup (one line on stderr, exit 1).

Covered elsewhere: truncated MCAP, garbage inside an MCAP, a corrupted SQLite file and a
missing bag, one each (test/unit/cli/test_bag_play.py); a wrong joint type through the
can_bridge process (test/integration/test_bridge_process.py); a bad plugin type through
rm_robot (test/integration/test_host_process.py).
"""

from __future__ import annotations

import pathlib
import shutil
import threading
import uuid

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from rclpy.parameter import Parameter
from rm_base.bridge import CanBridgeNode
from rm_base.errors import ConfigError
from rm_base.host.node import RobotHost
from rm_bringup.cli.bag_io import open_bag
from rm_bringup.cli.bag_play import PlayOptions, play
from rm_bringup.cli.bag_types import rm_bag_types
from rm_bringup.cli.errors import CliError
from rm_bringup.cli.main import main as rmcli
from rosbags.rosbag2 import StoragePlugin, Writer
from support.ros import start_process

S = 1_000_000_000
FILES = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """One good bag per storage: 300 std_msgs/String messages on two topics."""
    store = rm_bag_types().typestore
    String = store.types['std_msgs/msg/String']  # noqa: N806 (a message class)
    out = {}
    for storage in ('mcap', 'sqlite3'):
        path = tmp_path_factory.mktemp(storage) / 'bag'
        with Writer(path, version=9, storage_plugin=StoragePlugin[storage.upper()]) as writer:
            conns = [
                writer.add_connection(t, 'std_msgs/msg/String', typestore=store)
                for t in ('/a', '/b')
            ]
            for i in range(300):
                data = store.serialize_cdr(String(data='x' * (10 + i % 50)), 'std_msgs/msg/String')
                writer.write(conns[i % 2], S + i * 10_000_000, data)
        out[storage] = path
    return out


def copy(bag: pathlib.Path, tmp: pathlib.Path) -> pathlib.Path:
    target = tmp / f'bag-{uuid.uuid4().hex[:8]}'
    shutil.copytree(bag, target)
    return target


def data_file(bag: pathlib.Path) -> pathlib.Path:
    return next(p for p in bag.iterdir() if p.suffix in ('.mcap', '.db3'))


class Sink:
    def publish(self, data):
        pass


def read_all(bag: pathlib.Path) -> int:
    """Run the play loop over every message as fast as it goes; return the count."""
    with open_bag(bag) as reader:
        topics = {c.topic for c in reader.connections}
        return play(
            reader,
            bag,
            reader.connections,
            {t: Sink() for t in topics},
            options=PlayOptions(rate=1e9),
            stop=threading.Event(),
        )


def assert_clean(bag: pathlib.Path, capsys) -> None:
    """bag info and the play loop: fine, or one clear error; never an exception."""
    code = rmcli(['bag', 'info', str(bag)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code in (0, 1)
    if code == 1:
        assert len(err) == 1 and err[0].startswith('rmcli: error: '), err
    try:
        read_all(bag)
    except CliError as error:
        assert '\n' not in str(error).strip()


@FILES
@given(storage=st.sampled_from(['mcap', 'sqlite3']), fraction=st.floats(0.0, 1.0))
def test_a_bag_truncated_anywhere_is_read_or_one_clear_error(
    bags, tmp_path, capsys, storage, fraction
):
    bag = copy(bags[storage], tmp_path)
    path = data_file(bag)
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])
    assert_clean(bag, capsys)


@FILES
@given(
    storage=st.sampled_from(['mcap', 'sqlite3']),
    edits=st.lists(st.tuples(st.floats(0.0, 1.0), st.binary(min_size=1, max_size=64)), max_size=4),
)
# found in CI: a NULL timestamp in a sqlite3 row reached the play loop as None
@example(storage='sqlite3', edits=[(0.533803397596652, b'\x00')])
def test_a_bag_with_bytes_overwritten_is_read_or_one_clear_error(
    bags, tmp_path, capsys, storage, edits
):
    bag = copy(bags[storage], tmp_path)
    path = data_file(bag)
    data = bytearray(path.read_bytes())
    for where, junk in edits:
        at = int(where * (len(data) - 1))
        data[at : at + len(junk)] = junk
    path.write_bytes(bytes(data))
    assert_clean(bag, capsys)


@FILES
@given(cut=st.floats(0.0, 1.0), junk=st.text(max_size=20))
def test_a_damaged_metadata_yaml_is_read_or_one_clear_error(bags, tmp_path, capsys, cut, junk):
    bag = copy(bags['mcap'], tmp_path)
    meta = bag / 'metadata.yaml'
    text = meta.read_text()
    at = int(len(text) * cut)
    meta.write_text(text[:at] + junk + text[at + len(junk) :])
    assert_clean(bag, capsys)


# --- config files ------------------------------------------------------------------------------

BRIDGE_OK = {
    'sim': True,
    'buses.can0.interface': 'rm_sim',
    'joints.w.type': 'm3508',
    'joints.w.bus': 'can0',
    'joints.w.id': 1,
}


@pytest.mark.ros
@pytest.mark.parametrize(
    ('change', 'match'),
    [
        ({'joints.w.bus': None}, r'joints\.w\.bus is required'),  # missing key
        ({'joints.w.id': 'one'}, r"joints\.w\.id must be integer; got str 'one'"),
        ({'joints.w.max_effort': 'lots'}, r'joints\.w\.max_effort must be double \[N·m\]; got str'),
        ({'safety.command_timeout_s': 'soon'}, r"'safety\.command_timeout_s' must be double"),
        ({'sim': False, 'buses.can0.interface': None}, r'buses\.can0\.interface is required'),
    ],
)
def test_a_bridge_config_with_a_missing_key_or_wrong_type_names_it(ros_context, change, match):
    params = {**BRIDGE_OK, 'buses.can0.channel': f'rm-rel-cfg-{uuid.uuid4().hex[:8]}', **change}
    overrides = [Parameter(k, value=v) for k, v in params.items() if v is not None]
    with pytest.raises(ConfigError, match=match):
        CanBridgeNode(context=ros_context, parameter_overrides=overrides)


@pytest.mark.ros
@pytest.mark.parametrize(
    ('params', 'match'),
    [
        ({}, r"parameter 'plugins'"),  # missing
        ({'plugins': ['chassis']}, r"'chassis\.type'"),  # the plugin's type missing
        (
            {
                'plugins': ['chassis'],
                'chassis.type': 'rm_plugins/StandChassis',
                'chassis.rate': 'x',
            },
            r"'chassis\.rate' must be double",
        ),
    ],
)
def test_a_host_config_with_a_missing_key_or_wrong_type_names_it(ros_context, params, match):
    with pytest.raises(ConfigError, match=match):
        RobotHost(
            context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()],
        )


BROKEN_YAML = 'can_bridge:\n  ros__parameters:\n    buses: {can0: {interface: rm_sim\n'
MISSING = 'can_bridge:\n  ros__parameters:\n    joints: {w: {type: m3508, bus: can0, id: 1}}\n'


def run_tool(args, timeout=30.0):
    proc = start_process(args)
    _, err = proc.communicate(timeout=timeout)
    lines = [line for line in err.splitlines() if line.strip() and '[INFO]' not in line]
    return proc.returncode, lines, err


def console_script(package, name):
    from ament_index_python.packages import get_package_prefix

    return str(pathlib.Path(get_package_prefix(package)) / 'lib' / package / name)


@pytest.mark.ros
@pytest.mark.slow
def test_a_bridge_params_file_without_buses_is_one_line_and_exit_1(tmp_path):
    path = tmp_path / 'missing.yaml'
    path.write_text(MISSING)
    code, lines, err = run_tool(
        [console_script('rm_base', 'can_bridge'), '--ros-args', '--params-file', str(path)]
    )
    assert code == 1 and len(lines) == 1 and 'Traceback' not in err, err
    assert lines[0].startswith('[can_bridge] configuration error: buses')


@pytest.mark.ros
@pytest.mark.slow
@pytest.mark.parametrize('tool', ['can_bridge', 'rm_robot', 'bringup'])
def test_a_params_file_that_is_not_yaml_is_one_line_and_exit_1(tmp_path, tool):
    path = tmp_path / 'robot.yaml'
    path.write_text(BROKEN_YAML)
    if tool == 'bringup':
        args = [console_script('rm_bringup', 'bringup'), '--config', str(path)]
    else:
        args = [console_script('rm_base', tool), '--ros-args', '--params-file', str(path)]
    code, lines, err = run_tool(args)
    assert code == 1
    assert 'Traceback' not in err and len(lines) == 1, err


@pytest.mark.ros
@pytest.mark.slow
@pytest.mark.parametrize(('content', 'message'), [
    (bytes(range(256)), 'is not a text file'),
    (b'imu:\n  imu: {gyro_bias: [5.0, 0.0, 0.0]}\n',
     'imu.imu.gyro_bias is [5.0, 0.0, 0.0]: beyond'),
], ids=['binary', 'gyro-bias-5-rad-s'])
def test_a_bad_calibration_file_is_one_line_naming_it_and_exit_1(tmp_path, content, message):
    # The findings: a binary file crashed bringup (UnicodeDecodeError); a 5 rad/s gyro bias
    # loaded with an INFO line and the gimbal held a 0.24 rad offset.
    calibration = tmp_path / 'calibration.yaml'
    calibration.write_bytes(content)
    overlay = tmp_path / 'overlay.yaml'
    overlay.write_text(
        f'can_bridge:\n  ros__parameters:\n    calibration.file: {calibration}\n'
        f'rm_robot:\n  ros__parameters:\n    imu.calibration.file: {calibration}\n')
    code, lines, err = run_tool([console_script('rm_bringup', 'bringup'), '--sim', '--no-status',
                                 '--params-file', str(overlay)], timeout=60.0)
    assert code == 1 and 'Traceback' not in err, err
    errors = [line for line in lines if 'configuration error' in line]
    assert len(errors) == 1 and message in errors[0] and str(calibration) in errors[0], err
