"""Taking a message that lets go of the interpreter lock while DDS hands it over.

rclpy's take (what its executors call) keeps the GIL for the whole of ``rcl_take``. A take
can block: it waits for the reader's mutex, which Fast DDS's event thread holds while it
answers a participant that just appeared, and that answer can wait a third of a second
for the new participant's shared-memory port (docs/PERFORMANCE.md, "No DDS call from the
loop"). With the GIL held, that stops every Python thread of the process.

Here ``rcl_take_serialized_message``, rcl's own entry point for serialised messages, runs
through ctypes, which releases the GIL for the call; the bytes are then deserialised under
the GIL (one short C call), by this thread or by the one that uses the message. The
counterpart of :mod:`rm_base.ros.publish`.
"""

from __future__ import annotations

import ctypes
from typing import Any

from rclpy.serialization import deserialize_message

from rm_base.ros.publish import Allocator, SerializedMessage, load_function

#: Capacity a new buffer starts with [bytes]; rmw grows it for a larger message.
INITIAL_CAPACITY = 256

# rcl's return codes (rcl/types.h)
_RCL_RET_OK = 0
_RCL_RET_SUBSCRIPTION_TAKE_FAILED = 401


class TakeError(RuntimeError):
    """rcl refused to take (e.g. the subscription is not valid)."""


class _Gid(ctypes.Structure):
    _fields_ = (('implementation_identifier', ctypes.c_char_p),
                ('data', ctypes.c_uint8 * 16))  # RMW_GID_STORAGE_SIZE


class MessageInfo(ctypes.Structure):
    """rmw_message_info_t (rmw/types.h, Jazzy): who sent a taken message, with which number."""

    _fields_ = (
        ('source_timestamp', ctypes.c_int64),
        ('received_timestamp', ctypes.c_int64),
        ('publication_sequence_number', ctypes.c_uint64),
        ('reception_sequence_number', ctypes.c_uint64),
        ('publisher_gid', _Gid),
        ('from_intra_process', ctypes.c_bool),
    )


class SequenceGaps:
    """Counts messages a subscription never got, from the publishers' sequence numbers.

    Each publisher numbers what it publishes; a number skipped between two taken messages
    of one publisher is a message lost before it was taken (DDS's keep-last history
    overwritten during a flood, or the network). rmw implementations that give no numbers
    give 0, which counts nothing.
    """

    def __init__(self) -> None:
        self._last: dict[bytes, int] = {}
        self.lost = 0

    def note(self, info: MessageInfo) -> int:
        """Note a taken message's info; return how many of its publisher's were skipped."""
        number = int(info.publication_sequence_number)
        if number == 0:
            return 0
        gid = bytes(info.publisher_gid.data)
        last = self._last.get(gid)
        self._last[gid] = number
        if last is None or number <= last + 1:
            return 0  # the first, the next, or a publisher that started over
        skipped = number - last - 1
        self.lost += skipped
        return skipped


_rcl_take_serialized = load_function(
    'librcl.so',
    'rcl_take_serialized_message',
    (ctypes.c_void_p, ctypes.POINTER(SerializedMessage), ctypes.c_void_p, ctypes.c_void_p),
    ctypes.c_int,
)
_default_allocator = load_function('librcutils.so', 'rcutils_get_default_allocator', (), Allocator)
_array_init = load_function(
    'librcutils.so',
    'rcutils_uint8_array_init',
    (ctypes.POINTER(SerializedMessage), ctypes.c_size_t, ctypes.POINTER(Allocator)),
    ctypes.c_int,
)
_array_fini = load_function(
    'librcutils.so', 'rcutils_uint8_array_fini', (ctypes.POINTER(SerializedMessage),), ctypes.c_int
)
_rcutils_reset_error = load_function('librcutils.so', 'rcutils_reset_error', (), None)


class TakeBuffer:
    """A serialised-message buffer rcl takes into, grown as messages need; one per thread.

    Its memory is rcutils' own (rmw resizes it with its allocator); :meth:`close` frees it.
    """

    def __init__(self, capacity: int = INITIAL_CAPACITY) -> None:
        self._message = SerializedMessage()
        allocator = _default_allocator()
        if _array_init(ctypes.byref(self._message), capacity, ctypes.byref(allocator)) != 0:
            _rcutils_reset_error()
            raise MemoryError(f'no {capacity}-byte buffer for taking messages')
        self._open = True

    def take(self, subscription: Any, msg_type: type) -> Any | None:
        """Take subscription's next message, without the GIL while rcl takes.

        Args:
            subscription: an rclpy ``Subscription``.
            msg_type: its message class.

        Returns:
            The message, or None when none was waiting.

        Raises:
            TakeError: rcl refused (a shut-down context is not refused: nothing waits).
            rclpy.exceptions.InvalidHandle: the subscription was destroyed.
        """
        data = self.take_serialized(subscription)
        return None if data is None else deserialize_message(data, msg_type)

    def take_serialized(
        self, subscription: Any, info: MessageInfo | None = None
    ) -> bytes | None:
        """Take subscription's next message as its serialised bytes (see :meth:`take`).

        For a thread that takes on behalf of another: deserialising is most of a take's
        cost, and the thread that uses the message pays it with its caches warm.
        info: filled with the message's sender and sequence number, if given.
        """
        if not self._open:
            raise ValueError('take into a closed buffer')
        handle = subscription.handle
        info_ref = ctypes.byref(info) if info is not None else None
        with handle:  # rclpy does not destroy it while in use
            ret = _rcl_take_serialized(handle.pointer, ctypes.byref(self._message), info_ref,
                                       None)
        if ret == _RCL_RET_SUBSCRIPTION_TAKE_FAILED:
            _rcutils_reset_error()
            return None
        if ret != _RCL_RET_OK:
            _rcutils_reset_error()  # rcl left its error in this thread's state
            raise TakeError(f'taking from {subscription.topic_name} failed: rcl returned {ret}')
        return ctypes.string_at(self._message.buffer, self._message.buffer_length)

    def close(self) -> None:
        """Free the buffer (idempotent)."""
        if self._open:
            self._open = False
            _array_fini(ctypes.byref(self._message))

    def __del__(self) -> None:
        self.close()
