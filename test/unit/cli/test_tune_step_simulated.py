"""rmcli tune step: whether the stepped joint is simulated, so a slip report is awaited."""

import pytest
from rm_bringup.cli.tune_step import _simulated


class Bridge:
    def __init__(self, **params):
        self.params = params

    def get(self, key):
        return self.params.get(key)


class Node:
    def __init__(self, *names):
        self.names = list(names)

    def get_node_names(self):
        return self.names


@pytest.mark.parametrize(
    ('bridge', 'nodes', 'simulated'),
    [
        # the world in the bridge
        (Bridge(sim=True), (), True),
        # make run: the world in rm_sim, the bridge on its socket; rm_sim's node not
        # discovered yet (the flaky case: no slip was waited for)
        (Bridge(**{'sim': False, 'joints.yaw.bus': 'can0',
                   'buses.can0.interface': 'rm_sim_socket'}), (), True),
        # --sim-can: a kernel interface; only rm_sim's node says it
        (Bridge(**{'sim': False, 'joints.yaw.bus': 'can0',
                   'buses.can0.interface': 'socketcan'}), ('can_bridge', 'rm_sim'), True),
        # a robot
        (Bridge(**{'sim': False, 'joints.yaw.bus': 'can0',
                   'buses.can0.interface': 'socketcan'}), ('can_bridge', 'rm_robot'), False),
    ],
)
def test_a_joint_is_simulated_if_the_bridge_its_bus_or_rm_sim_says_so(bridge, nodes, simulated):
    assert _simulated(Node(*nodes), bridge, 'yaw') is simulated
