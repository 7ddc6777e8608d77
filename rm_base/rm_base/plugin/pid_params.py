"""The form of a plugin's PID loop, chosen by its parameters: positional or incremental.

A plugin declares its loop's gains as a positional PID (``<group>.kp`` ...) and then calls
:func:`loop_pid`, which adds ``<group>.form`` and the incremental form's setpoint tracking
differentiator (docs/PARAMETERS.md lists them). The same choice for a joint's loops in
can_bridge is its config mapping (:func:`rm_base.control.pid_form.pid_config`).
"""

from __future__ import annotations

from rm_base.control.pid import PidGains
from rm_base.control.pid_form import INCREMENTAL, POSITIONAL, PidConfig, incremental_like
from rm_base.control.tracking_differentiator import TdParams
from rm_base.plugin.params import PluginParams


def loop_pid(p: PluginParams, group: str, gains: PidGains, *, setpoint_unit: str) -> PidConfig:
    """Declare ``<group>.form`` and the TD keys; return the loop's PID config.

    Args:
        p: the plugin's parameters.
        group: the loop's key prefix, e.g. ``yaw_pid``.
        gains: the loop's gains as read from ``<group>.*`` (positional form).
        setpoint_unit: unit of the setpoint, e.g. ``rad``.

    Raises:
        ParameterError: a TD key is set while the form is positional.
    """
    form = p.string(
        f'{group}.form', POSITIONAL, choices=(POSITIONAL, INCREMENTAL),
        description=f'{group}: positional PID, or the incremental (velocity-form) PID of '
        'RoboMaster firmware with kp, ki, kd and the output limit (the positional-only '
        'keys do not apply to it)',
    )
    acceleration = p.double(
        f'{group}.td_acceleration_limit', 0.0, ge=0.0, unit=f'{setpoint_unit}/s^2',
        description=f'{group}, incremental form: a tracking differentiator turns setpoint '
        'steps into ramps of at most this acceleration; 0: no TD',
    )
    filter_factor = p.double(
        f'{group}.td_filter_factor', 0.0, ge=0.0, unit='s',
        description=f'{group}, incremental form: the TD filter factor h0; 0: the loop period',
    )
    if form == POSITIONAL:
        for name, value in (('td_acceleration_limit', acceleration),
                            ('td_filter_factor', filter_factor)):
            if value:
                raise p.error(f'{group}.{name}', f'applies to the {INCREMENTAL} form only; '
                              f'set {p.key(group)}.form: {INCREMENTAL} or remove it')
        return gains
    if filter_factor and not acceleration:
        raise p.error(f'{group}.td_filter_factor', 'needs td_acceleration_limit > 0')
    td = TdParams(acceleration, filter_factor or None) if acceleration else None
    return incremental_like(gains, td)
