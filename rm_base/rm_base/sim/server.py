"""SimServer: a simulated world's CAN channels served on an AF_UNIX SOCK_SEQPACKET socket.

The motors of a robot run in a process of their own (``rm_sim``, :mod:`rm_base.sim.main`)
as real motors run on their own MCUs: the robot's python-can buses
(:mod:`rm_base.sim.socket_bus`) connect here, say which channel they are on, and from
then on every datagram they send is put on that channel, and every physics tick's frames
of the channel go back to them in one datagram (:mod:`rm_base.sim.wire`).

Threads: the world's physics thread (it delivers to the connections, under the world's
lock; a send that would block is dropped and counted, as a full socketcan buffer drops
frames), and one thread that accepts connections and reads what they send. A bus-off
fault injected on a channel answers every datagram from it with a bus-off error frame and
puts nothing on the bus.
"""

from __future__ import annotations

import logging
import os
import selectors
import socket
import threading
from collections.abc import Sequence
from pathlib import Path

import can

from rm_base.sim import wire
from rm_base.sim.channel import SimChannel
from rm_base.sim.world import SimWorld
from rm_base.sim_devices.errors import SimError, SimLookupError

_log = logging.getLogger(__name__)

_MAX_DATAGRAM = 65536
_SNDBUF_BYTES = 4 * 1024 * 1024
#: How often the server thread checks for stop() [s].
_POLL_S = 0.1


class _Connection:
    """One robot bus on one channel: the channel's endpoint for that bus."""

    receive_own_messages = False

    def __init__(self, sock: socket.socket, channel: SimChannel) -> None:
        self.sock = sock
        self.channel = channel
        self.dropped = 0

    def _deliver(self, msg: can.Message) -> None:
        self._deliver_all((msg,))

    def _deliver_all(self, msgs: Sequence[can.Message]) -> None:
        # The physics thread, under the world's lock: never block here.
        try:
            self.sock.send(wire.encode(msgs, msgs[0].timestamp or 0.0), socket.MSG_DONTWAIT)
        except BlockingIOError:
            self.dropped += len(msgs)
        except OSError:
            self.dropped += len(msgs)  # the bus went away; the reader thread cleans up


class SimServer:
    """Serves the channels of a world on a socket (see the module docstring).

    Args:
        world: the simulated world (its channels exist already).
        path: the socket's path; a stale socket file there is replaced.
    """

    def __init__(self, world: SimWorld, path: str | Path) -> None:
        self.world = world
        self.path = str(path)
        Path(self.path).parent.mkdir(parents=True, exist_ok=True)
        if os.path.exists(self.path):
            os.unlink(self.path)
        self._listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._listener.bind(self.path)
        self._listener.listen(16)
        self._listener.setblocking(False)
        self._selector = selectors.DefaultSelector()
        self._selector.register(self._listener, selectors.EVENT_READ)
        self._connections: dict[socket.socket, _Connection | None] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='rm_sim-server', daemon=True)
        self.connected = 0  # buses that said hello, in all
        self.datagrams = 0  # frame datagrams received, in all

    def start(self) -> None:
        """Accept connections and read them in a thread."""
        self._thread.start()

    def stop(self) -> None:
        """Close every connection and the socket (idempotent)."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
        for sock, connection in list(self._connections.items()):
            self._close(sock, connection)
        self._selector.close()
        self._listener.close()
        if os.path.exists(self.path):
            os.unlink(self.path)

    def _run(self) -> None:
        while not self._stop.is_set():
            for key, _ in self._selector.select(_POLL_S):
                sock = key.fileobj
                if sock is self._listener:
                    self._accept()
                elif isinstance(sock, socket.socket):  # every registered object is one
                    self._read(sock)

    def _accept(self) -> None:
        try:
            sock, _ = self._listener.accept()
        except BlockingIOError:
            return
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, _SNDBUF_BYTES)
        sock.setblocking(False)
        self._connections[sock] = None
        self._selector.register(sock, selectors.EVENT_READ)

    def _read(self, sock: socket.socket) -> None:
        connection = self._connections.get(sock)
        try:
            datagram = sock.recv(_MAX_DATAGRAM)
        except BlockingIOError:
            return
        except OSError:
            datagram = b''
        if not datagram:
            self._close(sock, connection)
            return
        if connection is None:
            self._hello(sock, datagram)
            return
        self.datagrams += 1
        try:
            frames = wire.decode(datagram, connection.channel.name)
        except wire.WireError as err:
            _log.warning('rm_sim: %s sent a bad datagram: %s', connection.channel.name, err)
            return
        channel = connection.channel
        if channel.state is can.BusState.ERROR:
            self._send_bus_off(sock)
            return
        for frame in frames:
            try:
                channel.send(connection, frame, None)
            except can.CanOperationError:  # bus-off injected meanwhile
                self._send_bus_off(sock)
                return

    def _hello(self, sock: socket.socket, datagram: bytes) -> None:
        if not datagram.startswith(wire.HELLO):
            self._answer(sock, wire.ERR + b'expected a hello')
            self._close(sock, None)
            return
        name = datagram.removeprefix(wire.HELLO).decode(errors='replace')
        try:
            channel = self.world.channel(name)
        except SimLookupError as err:
            self._answer(sock, wire.ERR + str(err).encode())
            self._close(sock, None)
            return
        connection = _Connection(sock, channel)
        try:
            channel.attach(connection)
        except SimError as err:
            self._answer(sock, wire.ERR + str(err).encode())
            self._close(sock, None)
            return
        self._connections[sock] = connection
        self.connected += 1
        self._answer(sock, wire.OK)
        _log.info('rm_sim: a bus joined %s', name)

    @staticmethod
    def _answer(sock: socket.socket, data: bytes) -> None:
        try:
            sock.send(data)
        except OSError:
            pass  # it left already

    def _send_bus_off(self, sock: socket.socket) -> None:
        try:
            sock.send(wire.encode((wire.bus_off_frame(),), self.world.timestamp()),
                      socket.MSG_DONTWAIT)
        except OSError:
            pass

    def _close(self, sock: socket.socket, connection: _Connection | None) -> None:
        self._connections.pop(sock, None)
        if connection is not None:
            connection.channel.detach(connection)
        try:
            self._selector.unregister(sock)
        except (KeyError, ValueError):
            pass
        sock.close()
