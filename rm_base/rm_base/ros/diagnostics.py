"""A diagnostic_msgs/DiagnosticStatus from plain values, as every /diagnostics of rm_base has it.

Each value is a ``KeyValue`` whose key carries its unit; a float is written with six
significant digits, NaN as ``nan``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue


def key_value(key: str, value: Any) -> KeyValue:
    """One KeyValue: value as text."""
    if isinstance(value, float):
        text = 'nan' if math.isnan(value) else f'{value:.6g}'
    else:
        text = str(value)
    return KeyValue(key=key, value=text)


def diagnostic_status(
    name: str, level: bytes, message: str, hardware_id: str, values: Mapping[str, Any]
) -> DiagnosticStatus:
    """A DiagnosticStatus with values in their order."""
    return DiagnosticStatus(
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[key_value(k, v) for k, v in values.items()],
    )
