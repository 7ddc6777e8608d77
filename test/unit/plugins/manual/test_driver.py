"""Operator input -> commands under the default mapping: modes, sticks, keys, toggles, loss."""

import pytest
from rm_base.hardware.protocols.dbus import DbusFrame, Key, Switch
from rm_plugins.manual.driver import Keyboard, ManualDriver, OperatorInput, passive
from rm_plugins.manual.mapping import load_mapping

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd


@pytest.fixture
def driver():
    return ManualDriver(load_mapping())


def frame(**fields):
    return DbusFrame(**fields)


def operator(driver, **fields):
    return OperatorInput.from_dbus(frame(**fields), driver.mapping)


def test_the_right_switch_down_is_every_mechanism_passive(driver):
    c = driver.commands(operator(driver, switch_a=Switch.DOWN, channels=(660, 660, 660, 660)))
    assert c == passive()


def test_sticks_scale_to_velocities_and_rates_and_the_left_switch_picks_the_shooter(driver):
    c = driver.commands(operator(driver, switch_a=Switch.MID, switch_b=Switch.MID,
                                 channels=(330, -660, 660, 330)))
    assert (c.chassis_mode, c.gimbal_mode, c.shoot_mode) == (
        ChassisCmd.FOLLOW, GimbalCmd.RATE, ShootCmd.READY)
    assert (c.vx, c.vy) == pytest.approx((1.0, -2.0))
    assert (c.yaw_rate, c.pitch_rate) == pytest.approx((-2.0, 3.0))
    assert (c.bullet_speed, c.hz) == (15.0, 10.0)


def test_each_push_of_the_left_switch_starts_a_new_burst(driver):
    ids = []
    for left in (Switch.UP, Switch.UP, Switch.MID, Switch.UP):
        c = driver.commands(operator(driver, switch_a=Switch.MID, switch_b=left))
        ids.append((c.shoot_mode, c.burst_id))
    assert ids == [(ShootCmd.PUSH, 1), (ShootCmd.PUSH, 1), (ShootCmd.READY, 1),
                   (ShootCmd.PUSH, 2)]


def test_wasd_with_gears_and_the_mouse_aim(driver):
    c = driver.commands(operator(driver, switch_a=Switch.UP, keys=Key.W | Key.A | Key.SHIFT,
                                 mouse=(10, -5, 0)))
    # the keyboard speed as it is; the gear asks the chassis for its FAST factors
    assert (c.vx, c.vy, c.speed_gear) == pytest.approx((2.0, 2.0, ChassisCmd.GEAR_FAST))
    assert (c.yaw_rate, c.pitch_rate) == pytest.approx((-0.2, -0.1))
    c = driver.commands(operator(driver, switch_a=Switch.UP, keys=Key.S | Key.D | Key.CTRL))
    assert (c.vx, c.vy, c.speed_gear) == pytest.approx((-2.0, -2.0, ChassisCmd.GEAR_SLOW))
    c = driver.commands(operator(driver, switch_a=Switch.UP, keys=Key.W))
    assert (c.vx, c.speed_gear) == pytest.approx((2.0, ChassisCmd.GEAR_NORMAL))


def test_mode_keys_and_the_friction_key_toggle_on_each_press(driver):
    def press(keys, **fields):
        return driver.commands(operator(driver, switch_a=Switch.UP, keys=keys, **fields))

    assert press(0).shoot_mode == ShootCmd.PASSIVE
    assert press(Key.F).chassis_mode == ChassisCmd.GYRO
    assert press(Key.F).chassis_mode == ChassisCmd.GYRO  # held: no new press
    assert press(0).chassis_mode == ChassisCmd.GYRO
    assert press(Key.G).chassis_mode == ChassisCmd.TWIST  # another mode key switches
    press(0)
    assert press(Key.G).chassis_mode == ChassisCmd.FOLLOW  # the same key again: back
    assert press(0, mouse_left=True).shoot_mode == ShootCmd.PASSIVE  # no fire: friction off
    assert press(Key.R).shoot_mode == ShootCmd.READY
    c = press(0, mouse_left=True)
    assert (c.shoot_mode, c.burst_id) == (ShootCmd.PUSH, 1)
    assert press(0).shoot_mode == ShootCmd.READY
    press(Key.R)
    assert press(0, mouse_left=True).shoot_mode == ShootCmd.PASSIVE


def test_the_image_links_keyboard_and_mouse_add_to_the_remotes(driver):
    base = operator(driver, switch_a=Switch.UP, keys=Key.W, mouse=(5, 0, 0))
    c = driver.commands(base.plus_keyboard(Keyboard(5, 10, False, True, int(Key.A))))
    assert (c.vx, c.vy) == pytest.approx((2.0, 2.0))
    assert (c.yaw_rate, c.pitch_rate) == pytest.approx((-0.2, 0.2))


def test_a_lost_remote_is_passive_and_forgets_the_toggles(driver):
    driver.commands(operator(driver, switch_a=Switch.UP, keys=Key.F | Key.R))
    assert driver.lost() == passive()
    c = driver.commands(operator(driver, switch_a=Switch.UP))
    assert (c.chassis_mode, c.shoot_mode) == (ChassisCmd.FOLLOW, ShootCmd.PASSIVE)
