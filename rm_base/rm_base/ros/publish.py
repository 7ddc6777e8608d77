"""Publishing that lets go of the interpreter lock while DDS sends.

rclpy's ``Publisher.publish`` keeps the GIL for the whole of ``rcl_publish``, and Fast DDS
sends in the caller's thread. A send can block: the first message to a participant that
just appeared opens that participant's shared-memory port, and the port's health check
sleeps a third of a second when the new process is not yet listening on it. With the GIL
held, that stops every Python thread of the process, the control loop among them
(docs/PERFORMANCE.md, "No DDS call from the loop").

Here the message is serialised under the GIL (one short C call), and the bytes go to
``rcl_publish_serialized_message``, rcl's own entry point for serialised messages, through
ctypes, which releases the GIL for the call. A send that blocks then holds up only the
thread that publishes and what waits on Fast DDS's own locks meanwhile (a take on a reader
that is answering the new participant still does: the same section of docs/PERFORMANCE.md).
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from typing import Any

from rclpy.publisher import Publisher
from rclpy.serialization import serialize_message


class PublishError(RuntimeError):
    """rcl refused to publish (the publisher or its context is gone)."""


class Allocator(ctypes.Structure):
    """rcutils_allocator_t."""

    _fields_ = [
        ('allocate', ctypes.c_void_p),
        ('deallocate', ctypes.c_void_p),
        ('reallocate', ctypes.c_void_p),
        ('zero_allocate', ctypes.c_void_p),
        ('state', ctypes.c_void_p),
    ]


class SerializedMessage(ctypes.Structure):
    """rcl_serialized_message_t (rcutils_uint8_array_t)."""

    _fields_ = [
        ('buffer', ctypes.c_void_p),
        ('buffer_length', ctypes.c_size_t),
        ('buffer_capacity', ctypes.c_size_t),
        ('allocator', Allocator),
    ]


def load_function(library: str, name: str, argtypes: Sequence[Any], restype: Any) -> Any:
    """A C function that releases the GIL while it runs (ctypes.CDLL, not PyDLL).

    library: a shared library's name; one rclpy loaded already is the same copy.
    """
    function = getattr(ctypes.CDLL(library), name)
    function.argtypes = list(argtypes)
    function.restype = restype
    return function


_rcl_publish_serialized = load_function(
    'librcl.so',
    'rcl_publish_serialized_message',
    (ctypes.c_void_p, ctypes.POINTER(SerializedMessage), ctypes.c_void_p),
    ctypes.c_int,
)
_rcutils_reset_error = load_function('librcutils.so', 'rcutils_reset_error', (), None)


def publish(publisher: Any, message: Any) -> None:
    """Publish message on an rclpy publisher, without the GIL while DDS sends.

    Args:
        publisher: an rclpy ``Publisher``; anything else with ``publish`` (a stand-in)
            publishes the message itself.
        message: a message of the publisher's type, or its serialised bytes.

    Raises:
        PublishError: rcl refused (e.g. the publisher was destroyed).
    """
    if not isinstance(publisher, Publisher):
        publisher.publish(message)
        return
    data = message if isinstance(message, bytes) else serialize_message(message)
    buffer = ctypes.c_char_p(data)  # the bytes' own storage, alive as long as data
    # rcl only reads the bytes: no allocator needed
    serialized = SerializedMessage(ctypes.cast(buffer, ctypes.c_void_p), len(data), len(data))
    handle = publisher.handle
    with handle:  # rclpy does not destroy it while in use
        ret = _rcl_publish_serialized(handle.pointer, ctypes.byref(serialized), None)
    if ret != 0:
        _rcutils_reset_error()  # rcl left its error in this thread's state
        raise PublishError(f'publishing on {publisher.topic_name} failed: rcl returned {ret}')
