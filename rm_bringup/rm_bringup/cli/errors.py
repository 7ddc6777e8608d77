"""Errors of the rmcli tool: each one is a user-facing, one-line message.

``main()`` prints a ``CliError`` as ``rmcli: error: <message>`` and exits with 1; argparse
reports usage errors itself and exits with 2. Anything else is a bug and keeps its
traceback.
"""

from rm_base.errors import RmError


class CliError(RmError):
    """A command could not do its job; the message says why, in one line.

    Example: the topic is not on the graph, a bag file is truncated, an output folder exists.
    """


class MessageTypeError(CliError, ValueError):
    """A message type name is malformed or its package/class cannot be imported.

    Example: ``rm_msgs/msg/ChasisCmd`` (typo), ``std_msgs`` (no message name).
    """


class MessageFieldError(CliError, ValueError):
    """Values given for a message do not fit it; the message names the field path.

    Example: ``{mode: GYR}`` for rm_msgs/msg/ChassisCmd, ``{accel: {linear: {x: abc}}}``.
    """


class BagError(CliError):
    """A bag cannot be opened, read or written; the message names the file.

    Example: a truncated .mcap file, a folder without metadata.yaml.
    """


class UsageError(CliError):
    """The command line is inconsistent in a way argparse cannot see; exit code 2.

    Example: ``--max-wait-time-secs`` without anything to wait for, three positionals to pub.
    """
