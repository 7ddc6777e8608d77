"""``rmcli tune step``'s SlipWatch hears rm_sim's /diagnostics over DDS."""

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.executors import SingleThreadedExecutor
from rm_bringup.cli.sim_slip import SlipWatch
from support.ros import spinning

pytestmark = pytest.mark.ros


def test_the_slip_over_a_run_comes_from_the_simulators_reports(ros_context):
    bridge = rclpy.create_node('rm_sim', context=ros_context)
    publisher = bridge.create_publisher(DiagnosticArray, '/diagnostics', 10)  # as rm_sim's
    slipped = ['0.0']

    def report():
        publisher.publish(DiagnosticArray(status=[DiagnosticStatus(
            name='rm_sim: simulator', values=[KeyValue(key='slipped [s]',
                                                           value=slipped[0])])]))

    bridge.create_timer(0.2, report)
    cli = rclpy.create_node('tune_cli', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(cli)
    try:
        with spinning(bridge):
            watch = SlipWatch(cli, lambda: executor.spin_once(timeout_sec=0.05))
            before = None
            for _ in range(20):  # discovery: up to 20 waits of 2.5 s
                before = watch.start(True)
                if before is not None:
                    break
            assert before == 0.0
            slipped[0] = '0.35'  # the world slipped during the run
            assert watch.since(before) == pytest.approx(0.35)
    finally:
        executor.shutdown()
        cli.destroy_node()
        bridge.destroy_node()
