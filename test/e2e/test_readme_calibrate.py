"""README's "Calibrate", typed as written: the values are kept and read at the next start.

On `make run` the simulated barrel rests on its lower end stop: before, /joint_states has
the pitch there (about 0.35 rad); README's three service calls succeed and write the
simulated robot's calibration file under ROS_HOME; after a restart the pitch reads 0 at the
same place, and the file still holds the gyro bias.
"""

import pytest
import yaml
from support.user_session import UserSession, readme_blocks

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

PITCH = ('rmcli topic echo /joint_states sensor_msgs/msg/JointState --once --field name\n'
         'rmcli topic echo /joint_states sensor_msgs/msg/JointState --once --field position')


def pitch_of(output: str) -> float:
    """The pitch's position from the two echoes (the names, then the positions)."""
    names, positions = (yaml.safe_load(doc) for doc in output.split('---')[:2])
    return float(positions[names.index('pitch')])


def test_the_calibration_services_keep_their_values_across_a_restart(tmp_path):
    (block,) = readme_blocks('Calibrate')
    assert block.count('rmcli service call') == 3
    with UserSession(tmp_path) as user:
        user.wait_for_robot()
        before = pitch_of(user.type(PITCH, wait=True))
        assert 0.3 < before < 0.4, before  # on the end stop, at the config's zero
        said = user.type(block, wait=True, timeout=120.0)
        assert said.count('success=True') == 3, said
    kept = tmp_path / 'ros_home' / 'rm_ros2' / 'standard_sim_calibration.yaml'
    values = yaml.safe_load(kept.read_text())
    assert set(values['joints']) == {'yaw', 'pitch'} and 'gyro_bias' in values['imu']['imu']
    again = tmp_path / 'again'
    again.mkdir()
    (again / 'ros_home').symlink_to(tmp_path / 'ros_home')  # the same user, the same ~/.ros
    with UserSession(again) as user:
        user.wait_for_robot()
        after = pitch_of(user.type(PITCH, wait=True))
        assert abs(after) < 0.02, after  # the same place now reads zero
