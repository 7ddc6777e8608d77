"""Device protocols: bytes <-> physical values, both directions (host and device side).

Pure functions and immutable records, no I/O. Here: the protocols that are not one motor
family's (the shared MIT encoding, the HiPNUC IMU, the DR16 receiver); each motor family's
own is ``rm_base.motors.<family>.protocol``. The names inside a module are short
(``mit.pack_command``, ``hipnuc.decode_payload``), so import the module::

    from rm_base.hardware.protocols import mit
"""

from rm_base.hardware.protocols import dbus, hipnuc, mit
from rm_base.hardware.protocols.mit import (
    MitCommand,
    MitLimits,
    SystemCommand,
    float_to_uint,
    uint_to_float,
)

__all__ = [
    'MitCommand',
    'MitLimits',
    'SystemCommand',
    'dbus',
    'float_to_uint',
    'hipnuc',
    'mit',
    'uint_to_float',
]
