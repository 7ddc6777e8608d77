"""Shooter plugin (``rm_plugins/StandShooter``): friction wheels, slotted trigger, jam recovery."""

from rm_plugins.shooter.command import ShootCommand, ShooterStage, ShootMode, parse_shoot_cmd
from rm_plugins.shooter.config import ShooterConfig
from rm_plugins.shooter.plugin import StandShooter

__all__ = [
    'ShootCommand',
    'ShootMode',
    'ShooterConfig',
    'ShooterStage',
    'StandShooter',
    'parse_shoot_cmd',
]
