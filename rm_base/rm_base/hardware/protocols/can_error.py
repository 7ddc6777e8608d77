"""SocketCAN error frames: what the controller reports, decoded (docs/PROTOCOLS.md §7).

The kernel's CAN drivers report bus trouble as frames with the error flag set
(``linux/can/error.h``): the identifier's low bits say which classes of error occurred and
the eight data bytes say more about some of them::

    id  0x001 tx timeout    0x002 lost arbitration (data[0]: bit)
        0x004 controller    (data[1]: warning / passive / overflow / back to active)
        0x008 protocol      (data[2]: kind, data[3]: where in the frame)
        0x010 transceiver   0x020 no ACK    0x040 bus-off    0x080 bus error
        0x100 restarted     0x200 counters  (data[6]: tx, data[7]: rx error counter)

python-can hands such a frame over as a ``Message`` with ``is_error_frame`` and the
identifier's 29 bits in ``arbitration_id``. Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

CLASSES: tuple[tuple[int, str], ...] = (
    (0x001, 'tx-timeout'),
    (0x002, 'lost-arbitration'),
    (0x004, 'controller'),
    (0x008, 'protocol'),
    (0x010, 'transceiver'),
    (0x020, 'no-ack'),
    (0x040, 'bus-off'),
    (0x080, 'bus-error'),
    (0x100, 'restarted'),
    (0x200, 'counters'),
)
CONTROLLER: tuple[tuple[int, str], ...] = (
    (0x01, 'rx-overflow'),
    (0x02, 'tx-overflow'),
    (0x04, 'rx-warning'),
    (0x08, 'tx-warning'),
    (0x10, 'rx-passive'),
    (0x20, 'tx-passive'),
    (0x40, 'active'),
)
PROTOCOL: tuple[tuple[int, str], ...] = (
    (0x01, 'bit'),
    (0x02, 'form'),
    (0x04, 'stuff'),
    (0x08, 'bit0'),
    (0x10, 'bit1'),
    (0x20, 'overload'),
    (0x40, 'active-flag'),
    (0x80, 'while-transmitting'),
)
# Where in the frame a protocol error was seen (data[3]); the common places by name.
LOCATION: dict[int, str] = {
    0x03: 'start of frame',
    0x08: 'CRC sequence',
    0x0A: 'data',
    0x18: 'CRC delimiter',
    0x19: 'ACK slot',
    0x1A: 'end of frame',
    0x1B: 'ACK delimiter',
    0x12: 'intermission',
}
_CLASS_MASK = 0x3FF


@dataclass(frozen=True)
class CanErrorReport:
    """One error frame, decoded.

    Attributes:
        classes: the error classes set in the identifier, in bit order.
        controller: controller status flags (data[1]) when ``controller`` is set.
        protocol: protocol error kinds (data[2]) when ``protocol`` is set.
        location: where in the frame (data[3]) when ``protocol`` is set, else ''.
        tx_errors, rx_errors: the controller's error counters when ``counters`` is set.
    """

    classes: tuple[str, ...]
    controller: tuple[str, ...] = ()
    protocol: tuple[str, ...] = ()
    location: str = ''
    tx_errors: int | None = None
    rx_errors: int | None = None

    @property
    def bus_off(self) -> bool:
        """The controller went off the bus."""
        return 'bus-off' in self.classes

    def describe(self) -> str:
        """One line for a log or /diagnostics."""
        parts = [' '.join(self.classes) or 'unspecified']
        if self.controller:
            parts.append(f'controller {" ".join(self.controller)}')
        if self.protocol:
            where = f' at {self.location}' if self.location else ''
            parts.append(f'protocol {" ".join(self.protocol)}{where}')
        if self.tx_errors is not None:
            parts.append(f'counters tx {self.tx_errors} rx {self.rx_errors}')
        return ', '.join(parts)


def _flags(value: int, table: tuple[tuple[int, str], ...]) -> tuple[str, ...]:
    return tuple(name for bit, name in table if value & bit)


def decode_error_frame(can_id: int, data: bytes) -> CanErrorReport:
    """Decode an error frame's identifier (its 29 bits) and data.

    Up to 8 bytes are read; missing ones read as 0 (a driver's short frame has nothing
    more to say).
    """
    body = bytes(data[:8]).ljust(8, b'\0')
    classes = _flags(can_id & _CLASS_MASK, CLASSES)
    controller = _flags(body[1], CONTROLLER) if can_id & 0x004 else ()
    protocol = _flags(body[2], PROTOCOL) if can_id & 0x008 else ()
    location = ''
    if can_id & 0x008 and body[3]:
        location = LOCATION.get(body[3], f'location 0x{body[3]:02X}')
    tx = rx = None
    if can_id & 0x200:
        tx, rx = body[6], body[7]
    return CanErrorReport(classes, controller, protocol, location, tx, rx)
