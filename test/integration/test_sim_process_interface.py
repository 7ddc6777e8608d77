"""rm_sim started by bringup on a python-can interface (`bringup --sim --sim-can ...`).

On the kernel's socketcan the same path runs in test/kernel; here python-can's virtual
interface stands in: rm_sim opens a bus per channel, says so, and the robot's buses are
left as its config has them."""

from __future__ import annotations

import os

import pytest
import yaml
from rm_bringup.bringup import parameter_files
from rm_bringup.sim_process import SimProcess
from support.ros import isolate_ros_environment

pytestmark = [pytest.mark.ros, pytest.mark.realtime]


def test_rm_sim_on_an_interface_leaves_the_robots_buses_alone(tmp_path, monkeypatch):
    env = dict(os.environ)
    isolate_ros_environment(env)
    for key in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE'):
        monkeypatch.setenv(key, env[key])
    files = parameter_files('standard', None, sim=True)
    with SimProcess(files, tmp_path, interface='virtual') as sim:
        assert sim.process.poll() is None
        overlay = yaml.safe_load(sim.bridge_overlay.read_text())
        # under the relative and the absolute name, so that it wins over a dump's section
        assert overlay == {name: {'ros__parameters': {'sim': False}}
                           for name in ('can_bridge', '/can_bridge')}
        said = sim.log_path.read_text()
    assert '[rm_sim] can0, can1 on virtual' in said
    assert not (tmp_path / 'can.sock').exists()  # no socket: the buses are the interface's
