"""Which PID form a loop runs, chosen in its config: positional or incremental.

A loop's config is a mapping. ``form: positional`` (the default) takes the fields of
:class:`~rm_base.control.pid.PidGains`; ``form: incremental`` the velocity-form PID that
RoboMaster firmware runs (:class:`~rm_base.control.incremental_pid.IncrementalPid`:
``kp``, ``ki``, ``kd``, ``output_limit``) with an optional tracking differentiator on the
setpoint (``td_acceleration_limit`` [setpoint units/s²], ``td_filter_factor`` [s]).
Both controllers share ``update(setpoint, measurement, dt)`` and ``reset()``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from rm_base.control.incremental_pid import IncrementalPid, IncrementalPidGains
from rm_base.control.pid import Pid, PidGains
from rm_base.control.tracking_differentiator import TdParams
from rm_base.errors import ConfigError

POSITIONAL = 'positional'
INCREMENTAL = 'incremental'
_TD_KEYS = {'td_acceleration_limit': 'acceleration_limit', 'td_filter_factor': 'filter_factor_s'}


@dataclasses.dataclass(frozen=True, slots=True)
class IncrementalPidConfig:
    """An incremental PID's gains and the tracking differentiator on its setpoint, if any."""

    gains: IncrementalPidGains = dataclasses.field(default_factory=IncrementalPidGains)
    setpoint_td: TdParams | None = None

    @property
    def output_limit(self) -> float:
        """The output bound, as :attr:`PidGains.output_limit`."""
        return self.gains.output_limit

    @property
    def angle_mode(self) -> bool:
        """Whether the error is an angle, as :attr:`PidGains.angle_mode`."""
        return self.gains.angle_mode


PidConfig = PidGains | IncrementalPidConfig
Controller = Pid | IncrementalPid


def pid_config(data: Mapping[str, Any] | None) -> PidConfig:
    """The loop config of a mapping (None: a positional PID with zero gains).

    Raises:
        ConfigError: an unknown form or key, or an invalid value (the message names it).
    """
    if data is None:
        return PidGains()
    fields = dict(data)
    form = fields.pop('form', POSITIONAL)
    if form == POSITIONAL:
        _check_keys(fields, {f.name for f in dataclasses.fields(PidGains)}, form)
        return PidGains(**fields)
    if form != INCREMENTAL:
        raise ConfigError(f"form must be '{POSITIONAL}' or '{INCREMENTAL}', got {form!r}")
    gain_keys = {f.name for f in dataclasses.fields(IncrementalPidGains)}
    _check_keys(fields, gain_keys | set(_TD_KEYS), form)
    td = {_TD_KEYS[k]: fields.pop(k) for k in list(fields) if k in _TD_KEYS}
    if td and 'acceleration_limit' not in td:
        raise ConfigError('td_filter_factor needs td_acceleration_limit')
    return IncrementalPidConfig(IncrementalPidGains(**fields), TdParams(**td) if td else None)


def incremental_like(gains: PidGains, setpoint_td: TdParams | None = None) -> IncrementalPidConfig:
    """The incremental PID with the kp, ki, kd, output limit and angle mode of gains.

    The positional-only fields (integral limit and separation, deadband, D low-pass) have
    no incremental counterpart: the output limit bounds the integral.
    """
    return IncrementalPidConfig(
        IncrementalPidGains(gains.kp, gains.ki, gains.kd, gains.output_limit, gains.angle_mode),
        setpoint_td,
    )


def build_pid(config: PidConfig) -> Controller:
    """A controller at rest for a loop config."""
    if isinstance(config, IncrementalPidConfig):
        return IncrementalPid(config.gains, config.setpoint_td)
    return Pid(config)


def _check_keys(fields: Mapping[str, Any], known: set[str], form: str) -> None:
    unknown = sorted(set(fields) - known)
    if unknown:
        raise ConfigError(
            f'unknown key(s) {unknown} for a {form} PID; known: {sorted(known | {"form"})}'
        )
