"""SlipWatch: the simulated world's slip over a measurement, from /diagnostics."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rm_bringup.cli.sim_slip import SlipWatch, slipped_s


def report(slipped=None):
    status = [DiagnosticStatus(name='can_bridge: scheduler',
                               values=[KeyValue(key='overruns', value='3')])]
    if slipped is not None:
        status.append(DiagnosticStatus(name='can_bridge: simulator', values=[
            KeyValue(key='time [s]', value='12.0'), KeyValue(key='slipped [s]', value=slipped)]))
    return DiagnosticArray(status=status)


class Robot:
    """A node whose /diagnostics come at given times [s] of a clock that spin() moves."""

    def __init__(self, reports):
        self.now, self.reports, self.callback = 0.0, sorted(reports, key=lambda r: r[0]), None

    def create_subscription(self, msg_type, topic, callback, depth):
        assert (msg_type, topic) == (DiagnosticArray, '/diagnostics')
        self.callback = callback

    def spin(self):
        self.now += 0.05
        while self.reports and self.reports[0][0] <= self.now:
            self.callback(self.reports.pop(0)[1])

    def watch(self):
        return SlipWatch(self, self.spin, clock=lambda: self.now)


def test_the_slip_is_read_from_the_simulator_status_only():
    assert slipped_s(report('0.25')) == 0.25
    assert slipped_s(report()) is None
    assert slipped_s(report('not a number')) is None


def test_what_slipped_between_start_and_the_next_report_after_the_run():
    robot = Robot([(0.5, report('0.1')), (1.5, report('0.1')), (2.5, report('0.4')),
                   (3.5, report('0.4')), (4.5, report('0.9'))])
    watch = robot.watch()
    before = watch.start(True)  # waits for the first report
    assert before == 0.1 and robot.now < 0.6
    robot.now = 2.7  # the run: its last report came at 2.5 s
    assert watch.since(before) == 0.4 - 0.1  # the one at 3.5 s, after the run
    assert robot.now < 3.6


def test_reports_without_a_simulator_status_are_waited_past():
    robot = Robot([(0.2, report()), (0.7, report('0.1'))])  # the bridge's, then rm_sim's
    assert robot.watch().start(True) == 0.1


def test_a_robot_without_a_simulator_is_not_waited_for():
    robot = Robot([(0.5, report()), (1.5, report())])
    watch = robot.watch()
    assert watch.start(False) is None and robot.now == 0.0
    assert watch.since(None) is None and robot.now == 0.0


def test_a_simulator_that_never_reports_costs_one_wait_and_no_verdict():
    robot = Robot([(0.5, report())])
    watch = robot.watch()
    assert watch.start(True) is None
    assert 6.0 <= robot.now < 6.2  # discovery and a report period
    assert watch.since(None) is None


def test_a_first_report_that_discovery_delays_is_waited_for():
    # a new CLI process can take 2-2.5 s to discover rm_sim, then up to a report period
    robot = Robot([(3.4, report('0.1')), (4.4, report('0.1')), (5.4, report('0.7'))])
    watch = robot.watch()
    assert watch.start(True) == 0.1 and robot.now < 3.5
    while robot.now < 5.0:  # the step: the CLI spins, taking the report at 4.4 s
        robot.spin()
    assert abs(watch.since(0.1) - 0.6) < 1e-9  # from the one at 5.4 s


def test_without_a_report_after_the_run_the_last_one_is_used():
    robot = Robot([(0.5, report('0.0')), (1.0, report('0.2'))])
    watch = robot.watch()
    before = watch.start(True)
    robot.now = 1.2
    assert watch.since(before) == 0.2  # after the 2.5 s wait, from the report at 1 s
