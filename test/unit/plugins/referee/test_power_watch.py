"""The referee plugin says once why the robot lost power, and when it came back."""

from rm_base.hardware.protocols.referee import RobotStatus
from rm_plugins.referee.power_watch import PowerWatch


def status(hp=300, gimbal=True, chassis=True, shooter=True):
    return RobotStatus(1, 1, hp, 300, 40, 200, 100.0, gimbal, chassis, shooter)


def test_a_healthy_robot_says_nothing():
    watch = PowerWatch()
    assert [watch.note(status()) for _ in range(3)] == [None, None, None]


def test_each_change_is_said_once():
    watch = PowerWatch()
    said = [watch.note(s) for s in (
        status(), status(chassis=False), status(chassis=False), status(),
        status(hp=120, shooter=False), status(hp=0, gimbal=False, chassis=False, shooter=False),
        status(hp=0, gimbal=False, chassis=False, shooter=False), status(),
    )]
    assert said == [
        None,
        'referee: power off at chassis (a rule: chassis power or barrel heat)',
        None,
        'referee: power back at chassis',
        'referee: power off at shooter (a rule: chassis power or barrel heat)',
        'referee: robot destroyed (HP 0 of 300): every power output off until a revival',
        None,
        'referee: robot revived (HP 300 of 300)',
    ]


def test_the_first_status_says_what_is_already_off():
    watch = PowerWatch()
    assert watch.note(status(hp=0, gimbal=False, chassis=False, shooter=False)).startswith(
        'referee: robot destroyed')
