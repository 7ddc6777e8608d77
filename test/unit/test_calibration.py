"""The calibration file: written atomically per entry, read back, refused when malformed."""

import math
import threading

import pytest
from rm_base.config.calibration import (
    CalibrationError,
    CalibrationFile,
    finite_values,
    joint_zero_offsets,
)


def test_a_missing_file_is_an_empty_calibration(tmp_path):
    file = CalibrationFile(str(tmp_path / 'none.yaml'))
    assert file.read() == {} and joint_zero_offsets(file) == {}


def test_entries_are_written_one_at_a_time_and_the_others_kept(tmp_path):
    file = CalibrationFile(str(tmp_path / 'robot' / 'calibration.yaml'))  # dir made
    file.write('joints', 'yaw', {'zero_offset': 1.25})
    file.write('imu', 'imu', {'gyro_bias': [0.001, -0.002, 0.0]})
    file.write('joints', 'pitch', {'zero_offset': -0.5})
    file.write('joints', 'yaw', {'zero_offset': 1.5})
    assert joint_zero_offsets(file) == {'yaw': 1.5, 'pitch': -0.5}
    assert file.entries('imu', ('gyro_bias',)) == {'imu': {'gyro_bias': [0.001, -0.002, 0.0]}}
    assert file.path.read_text().startswith('# Written by')
    assert sorted(p.name for p in file.path.parent.iterdir()) == [
        'calibration.yaml', 'calibration.yaml.lock'  # no temporary file left behind
    ]


def test_writers_in_parallel_lose_nothing(tmp_path):
    path = str(tmp_path / 'calibration.yaml')

    def write(i):
        CalibrationFile(path).write('joints', f'j{i}', {'zero_offset': i / 4})

    threads = [threading.Thread(target=write, args=(i,)) for i in range(20)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert joint_zero_offsets(CalibrationFile(path)) == {f'j{i}': i / 4 for i in range(20)}


def test_the_path_expands_home_and_variables(monkeypatch, tmp_path):
    monkeypatch.setenv('RM_TEST_DIR', str(tmp_path))
    assert CalibrationFile('${RM_TEST_DIR}/c.yaml').path == tmp_path / 'c.yaml'


@pytest.mark.parametrize(
    ('text', 'message'),
    [
        ('joints: [1, 2', 'is not YAML'),
        ('- 1\n- 2\n', 'must be a mapping, not list'),
        ('joints: {yaw: 1.0}\n', 'joints must map names to their values'),
        ('joints: {yaw: {zero_offset: .nan}}\n', r'joints.yaw.zero_offset must be finite'),
        ("joints: {yaw: {zero_offset: 'left'}}\n", r'joints.yaw.zero_offset must be numbers'),
        ('joints: {yaw: {zero_offset: 40.0}}\n', r'joints.yaw.zero_offset is 40.0: beyond 6.28'),
        ('joints: {yaw: {zero_ofset: 1.0}}\n', r'joints.yaw.zero_ofset is not a calibration key'),
    ],
    ids=['not-yaml', 'not-a-mapping', 'entry-not-a-mapping', 'nan', 'text', 'implausible',
         'typo'],
)
def test_a_malformed_file_is_one_clear_error_naming_the_file(tmp_path, text, message):
    path = tmp_path / 'calibration.yaml'
    path.write_text(text)
    with pytest.raises(CalibrationError, match=message) as err:
        joint_zero_offsets(CalibrationFile(str(path)))
    assert str(path) in str(err.value)


def test_finite_values_checks_length_type_and_finiteness():
    assert finite_values('bias', [1, 2.5, 0], 3) == (1.0, 2.5, 0.0)
    for bad in ([1, 2], [1, 2, math.inf], [True, 0, 0], 'abc'):
        with pytest.raises(CalibrationError, match='bias'):
            finite_values('bias', bad, 3)


def test_a_binary_file_is_one_clear_error_not_a_traceback(tmp_path):
    # The finding: a binary calibration file crashed bringup with a UnicodeDecodeError.
    path = tmp_path / 'calibration.yaml'
    path.write_bytes(bytes(range(256)))
    with pytest.raises(CalibrationError, match='is not a text file') as err:
        joint_zero_offsets(CalibrationFile(str(path)))
    assert str(path) in str(err.value)


def test_finite_values_refuses_what_no_calibration_measures():
    assert finite_values('bias', [0.01, 0, -0.05], 3, limit=0.05) == (0.01, 0.0, -0.05)
    with pytest.raises(CalibrationError, match=r'bias is \[5.0, 0, 0\]: beyond 0.05'):
        finite_values('bias', [5.0, 0, 0], 3, limit=0.05)
