"""Device protocols: bytes <-> physical values, both directions (host and device side).

Pure functions and immutable records, no I/O. One module per device family; the names
inside a module are short (``dji.decode_feedback``, ``damiao.decode_feedback``), so import
the module::

    from rm_base.hardware.protocols import dji
    can_id, slot = dji.command_slot('c620', 1)
"""

from rm_base.hardware.protocols import cheetah, damiao, dbus, dji, hipnuc, mit, piper
from rm_base.hardware.protocols.dji import DjiFeedback, DjiKind, DjiSpec, make_dji_spec
from rm_base.hardware.protocols.mit import (
    MitCommand,
    MitLimits,
    SystemCommand,
    float_to_uint,
    uint_to_float,
)

__all__ = [
    'DjiFeedback',
    'DjiKind',
    'DjiSpec',
    'MitCommand',
    'MitLimits',
    'SystemCommand',
    'cheetah',
    'damiao',
    'dbus',
    'dji',
    'float_to_uint',
    'hipnuc',
    'make_dji_spec',
    'mit',
    'piper',
    'uint_to_float',
]
