"""``rm_sim_socket``: a python-can interface to the rm_sim process, as socketcan is to a bus.

``can.Bus(interface='rm_sim_socket', channel='can0', socket='/tmp/.../can.sock')`` connects
an AF_UNIX SOCK_SEQPACKET socket to a running ``rm_sim`` (:mod:`rm_base.sim.server`), which
simulates the motors of every channel in a process of its own. Frames cross as raw SocketCAN
frames (:mod:`rm_base.sim.wire`): one datagram per send, one per physics tick back. The
robot sees a bus like socketcan's: ``send`` raises ``can.CanOperationError`` while rm_sim
reports bus-off, and ``recv`` returns the motors' frames stamped when rm_sim put them on
its bus. Registered as the ``can.interface`` entry point ``rm_sim_socket`` of rm_base.

The socket path is the ``socket`` option, else ``$RM_SIM_SOCKET``, else
``/tmp/rm_sim_<ROS_DOMAIN_ID>/can.sock`` (:func:`default_socket_path`), where ``rm_sim``
listens by default.
"""

from __future__ import annotations

import collections
import os
import select
import socket
import time
from typing import Any

import can
from can.typechecking import CanFilters

from rm_base.sim import wire

#: The receive buffer asked for [bytes]: a second of feedback of a busy channel.
#: The python-can interface name this bus registers under (rm_base's setup.py).
INTERFACE_NAME = 'rm_sim_socket'
_RCVBUF_BYTES = 4 * 1024 * 1024
#: How long to wait for rm_sim's answer to the hello [s].
_HELLO_TIMEOUT_S = 5.0
#: Largest datagram read [bytes]: far more frames than one tick of any channel has.
_MAX_DATAGRAM = 65536


def default_socket_path() -> str:
    """Where rm_sim listens unless told otherwise (``$RM_SIM_SOCKET`` or per domain)."""
    path = os.environ.get('RM_SIM_SOCKET')
    if path:
        return path
    return f'/tmp/rm_sim_{os.environ.get("ROS_DOMAIN_ID", "0")}/can.sock'


class SimSocketBus(can.BusABC):
    """A python-can bus on a channel of the rm_sim process (see the module docstring).

    Attributes:
        channel_info: ``'rm_sim_socket <channel> at <path>'``.
        bus_off: rm_sim reported bus-off in its latest datagram.
    """

    def __init__(
        self,
        channel: str = 'can0',
        can_filters: CanFilters | None = None,
        receive_own_messages: bool = False,
        *,
        socket_path: str | None = None,
        **kwargs: Any,
    ) -> None:
        """Connect to rm_sim's channel.

        Args:
            channel: the simulated channel's name.
            can_filters: python-can filters.
            receive_own_messages: not supported (rm_sim never echoes); must be False.
            socket_path: rm_sim's socket (option ``socket`` in a bus config);
                default :func:`default_socket_path`.
            **kwargs: other python-can options (``bitrate``, ...), accepted and ignored.

        Raises:
            can.CanInitializationError: rm_sim is not there or has no such channel.
        """
        if receive_own_messages:
            raise can.CanInitializationError('rm_sim_socket does not echo sent frames')
        path = socket_path or kwargs.pop('socket', None) or default_socket_path()
        self.channel_info = f'rm_sim_socket {channel} at {path}'
        self._channel = str(channel)
        self._pending: collections.deque[can.Message] = collections.deque()
        self.bus_off = False
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, _RCVBUF_BYTES)
            sock.settimeout(_HELLO_TIMEOUT_S)
            sock.connect(path)
            sock.send(wire.HELLO + self._channel.encode())
            answer = sock.recv(_MAX_DATAGRAM)
        except OSError as err:
            sock.close()
            raise can.CanInitializationError(f'rm_sim at {path}: {err}') from err
        if answer != wire.OK:
            sock.close()
            reason = answer.removeprefix(wire.ERR).decode(errors='replace')
            raise can.CanInitializationError(f'rm_sim at {path}: channel {channel}: {reason}')
        sock.setblocking(False)
        self._sock = sock
        super().__init__(channel=channel, can_filters=can_filters, **kwargs)

    def fileno(self) -> int:
        """The socket, for python-can's notifier and select()."""
        return self._sock.fileno()

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Send one frame to rm_sim.

        Raises:
            can.CanOperationError: rm_sim reports bus-off, or the socket failed.
        """
        self.send_many([msg], timeout)

    def send_many(self, msgs: list[can.Message], timeout: float | None = None) -> None:
        """Send a tick's frames to rm_sim in one datagram.

        Raises:
            can.CanOperationError: rm_sim reports bus-off, or the socket failed.
        """
        if self.bus_off:
            raise can.CanOperationError(f'{self._channel}: bus-off')
        try:
            self._sock.send(wire.encode(msgs, time.time()))
        except OSError as err:
            raise can.CanOperationError(f'{self._channel}: send failed: {err}') from err

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if not self._pending:
            self._read(timeout)
        if not self._pending:
            return None, False
        return self._pending.popleft(), False

    def _read(self, timeout: float | None) -> None:
        """Take every datagram that has arrived (waiting up to timeout [s] for the first)."""
        sock = self._sock
        if timeout != 0.0:
            ready, _, _ = select.select([sock], [], [], timeout)
            if not ready:
                return
        while True:
            try:
                datagram = sock.recv(_MAX_DATAGRAM)
            except BlockingIOError:
                return
            except OSError as err:
                raise can.CanOperationError(f'{self._channel}: receive failed: {err}') from err
            if not datagram:
                raise can.CanOperationError(f'{self._channel}: rm_sim closed the connection')
            frames = wire.decode(datagram, self._channel)
            bus_off = any(f.is_error_frame and f.arbitration_id & wire.CAN_ERR_BUSOFF
                          for f in frames)
            self.bus_off = bus_off
            self._pending.extend(f for f in frames if not f.is_error_frame)

    @property
    def state(self) -> can.BusState:
        """ERROR while rm_sim reports bus-off, else ACTIVE."""
        return can.BusState.ERROR if self.bus_off else can.BusState.ACTIVE

    @state.setter
    def state(self, new_state: can.BusState) -> None:
        raise NotImplementedError('rm_sim sets the bus state (bus-off faults)')

    def shutdown(self) -> None:
        """Close the connection (idempotent)."""
        super().shutdown()
        self._sock.close()
