"""Referee records -> rm_msgs: SI units, and NaN (never 0) for what a season leaves out."""

import math

import pytest
from rm_base.hardware.protocols import referee as ref
from rm_plugins.referee import messages

from rm_msgs.msg import RefereeGameStatus, RefereeHurt


def test_every_record_type_has_a_topic_and_a_message():
    records = [
        ref.GameStatus(1, 4, 299, 1_700_000_000),
        ref.RobotStatus(3, 2, 180, 200, 40, 240, 60.0, True, True, True),
        ref.PowerHeat(57.0, 120, 0),
        ref.ShootData(1, 1, 10, 24.5),
        ref.ProjectileAllowance(100, 5, 456),
        ref.Hurt(2, 5),
        ref.KeyboardMouse(100, -50, 0, True, False, 0x0091),
        ref.decode_remote_payload(bytes.fromhex(
            '94 06 20 AF D8 A2 60 19 F9 FF 0F 00 00 00 01 20 02')),  # the V1 vector's
    ]
    assert {type(r) for r in records} == set(messages.TOPICS)
    topics = {messages.TOPICS[type(r)][0] for r in records}
    # both keyboard sources share one topic
    assert len(topics) == len(records) - 1 and all(t.startswith('referee/') for t in topics)
    for record in records:
        _, msg_type, convert = messages.TOPICS[type(record)]
        assert isinstance(convert(record), msg_type)


def test_game_status_keeps_its_values():
    msg = messages.game_status(ref.GameStatus(1, 4, 299, 1_700_000_000))
    assert (msg.game_type, msg.progress) == (1, RefereeGameStatus.PROGRESS_IN_MATCH)
    assert (msg.stage_remaining, msg.unix_time) == (299, 1_700_000_000)


def test_robot_status_limits_and_a_missing_speed_limit_is_nan():
    msg = messages.robot_status(ref.RobotStatus(103, 1, 150, 150, 40, 200, 60.0, True, False, True))
    assert (msg.robot_id, msg.barrel_cooling, msg.barrel_heat_limit) == (103, 40.0, 200.0)
    assert msg.chassis_power_limit == 60.0
    assert (msg.gimbal_power, msg.chassis_power, msg.shooter_power) == (True, False, True)
    assert math.isnan(msg.bullet_speed_limit)
    with_limit = ref.RobotStatus(103, 1, 150, 150, 40, 200, 60.0, True, True, False, 25.0)
    assert messages.robot_status(with_limit).bullet_speed_limit == 25.0


@pytest.mark.parametrize(
    ('record', 'volts', 'power', 'second_barrel'),
    [
        (ref.PowerHeat(57.0, 120, 0, 0, 24.0, 2.5, 60.0), 24.0, 60.0, 0.0),  # 2024
        (ref.PowerHeat(57.0, 120, 0, 0), math.nan, math.nan, 0.0),  # 2025: no electrics
        (ref.PowerHeat(60.0, 130, 0), math.nan, math.nan, math.nan),  # 2026: one 17 mm heat
    ],
)
def test_power_heat_reports_nan_for_what_the_season_leaves_out(record, volts, power, second_barrel):
    msg = messages.power_heat(record)
    assert msg.buffer_energy == record.buffer_energy_j
    assert msg.heat_17mm == float(record.heat_17mm)
    for got, expected in ((msg.chassis_voltage, volts), (msg.chassis_power, power),
                          (msg.heat_17mm_2, second_barrel)):
        assert got == expected or (math.isnan(got) and math.isnan(expected))


def test_shot_allowance_and_hurt():
    shot = messages.shot(ref.ShootData(2, 3, 4, 15.5))
    assert (shot.bullet_type, shot.launcher_id, shot.frequency, shot.speed) == (2, 3, 4.0, 15.5)
    allowance = messages.projectiles(ref.ProjectileAllowance(1, 2, 3))
    assert (allowance.allowance_17mm, allowance.gold, allowance.fortress_17mm) == (1, 3, 0)
    assert messages.hurt(ref.Hurt(2, 5)).cause == RefereeHurt.CAUSE_COLLISION
