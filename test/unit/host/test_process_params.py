"""rm_robot's process parameters (rm_base.host.process_params)."""

import pytest
import rclpy
from rclpy.parameter import Parameter
from rm_base.host.process_params import process_settings
from rm_base.plugin import ParameterError, PluginParams
from rm_base.runtime import realtime

pytestmark = pytest.mark.ros


@pytest.fixture
def settings_of(ros_context, monkeypatch):
    monkeypatch.setattr(realtime.os, 'sched_getaffinity', lambda pid: {0, 1, 2})
    nodes = []

    def read(**overrides):
        node = rclpy.create_node(
            'process_params_test', context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
        nodes.append(node)
        return process_settings(PluginParams(node, '', prefix=''))

    yield read
    for node in nodes:
        node.destroy_node()


def test_by_default_the_loop_runs_at_1khz_at_priority_on_the_last_but_one_cpu_idle_cpus_polling(
    settings_of,
):
    settings = settings_of()
    assert (settings.loop_rate, settings.loop_priority) == (1000.0, realtime.LOOP_PRIORITY)
    assert settings.edge_priority == realtime.EDGE_PRIORITY
    assert (settings.cpu_index, settings.cpu_latency_us) == (-2, 0)


def test_minus_one_asks_no_latency_and_one_cpu_off_pins_nothing(settings_of):
    settings = settings_of(cpu_latency_us=-1, one_cpu=False)
    assert (settings.cpu_index, settings.cpu_latency_us) == (None, None)


@pytest.mark.parametrize(
    'overrides, message',
    [
        ({'cpu': 3}, r'cpu: CPU index 3 is outside'),
        ({'cpu_latency_us': -2}, r"'cpu_latency_us'.*>= -1"),
        ({'loop_rate': 0.0}, r"'loop_rate'"),
    ],
)
def test_a_value_out_of_range_is_a_parameter_error_naming_it(settings_of, overrides, message):
    with pytest.raises(ParameterError, match=message):
        settings_of(**overrides)
