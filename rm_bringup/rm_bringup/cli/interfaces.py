"""Message type names <-> generated Python classes (rosidl's importlib convention).

``pkg/msg/Name`` (or the short ``pkg/Name``) lives in module ``pkg.msg`` as class ``Name``,
which is how ros2cli's ``get_message`` finds it. No rclpy import here.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

from .errors import MessageTypeError

_TYPE_NAME = re.compile(r'^([A-Za-z][\w]*)/(?:(msg)/)?([A-Za-z][\w]*)$')


def looks_like_type_name(text: str) -> bool:
    """Whether text has the shape of a message type name (``pkg/msg/Name`` or ``pkg/Name``)."""
    return _TYPE_NAME.match(text) is not None


def normalize_type_name(type_name: str) -> str:
    """Return the full ``pkg/msg/Name`` form of a message type name.

    Raises:
        MessageTypeError: type_name is not ``pkg/msg/Name`` or ``pkg/Name``.
    """
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise MessageTypeError(
            f"invalid message type '{type_name}': expected 'package/msg/Name' "
            "(e.g. 'rm_msgs/msg/ChassisCmd')"
        )
    package, _, name = match.groups()
    return f'{package}/msg/{name}'


def get_message_class(type_name: str) -> type:
    """Import and return the generated class of a message type.

    Args:
        type_name: ``pkg/msg/Name`` or ``pkg/Name``.

    Raises:
        MessageTypeError: malformed name, package not installed, or no such message.
    """
    package, _, name = normalize_type_name(type_name).split('/')
    cls: type = _import_interface(type_name, package, 'msg', name, 'get_fields_and_field_types')
    return cls


_SERVICE_NAME = re.compile(r'^([A-Za-z][\w]*)/(?:srv/)?([A-Za-z][\w]*)$')


def get_service_class(type_name: str) -> Any:
    """Import and return the generated class of a service type (``pkg/srv/Name``, ``pkg/Name``).

    Raises:
        MessageTypeError: malformed name, package not installed, or no such service.
    """
    match = _SERVICE_NAME.match(type_name)
    if match is None:
        raise MessageTypeError(
            f"invalid service type '{type_name}': expected 'package/srv/Name' "
            "(e.g. 'std_srvs/srv/Trigger')"
        )
    package, name = match.groups()
    return _import_interface(type_name, package, 'srv', name, 'Request')


def _import_interface(type_name: str, package: str, kind: str, name: str, mark: str) -> Any:
    # rosidl's layout: pkg.msg.Name / pkg.srv.Name, a class with `mark` among its attributes
    what = {'msg': 'message', 'srv': 'service'}[kind]
    try:
        module = importlib.import_module(f'{package}.{kind}')
    except ModuleNotFoundError as err:
        raise MessageTypeError(
            f"unknown {what} type '{type_name}': package '{package}' is not installed "
            '(or the workspace is not sourced)'
        ) from err
    cls = getattr(module, name, None)
    if not isinstance(cls, type) or not hasattr(cls, mark):
        raise MessageTypeError(f"unknown {what} type '{type_name}': {package} has no {what} {name}")
    return cls


def type_name_of(msg_class: type) -> str:
    """Return ``pkg/msg/Name`` for a generated message class."""
    package = msg_class.__module__.split('.')[0]
    return f'{package}/msg/{msg_class.__name__}'
