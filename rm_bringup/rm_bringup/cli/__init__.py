"""rmcli: ``topic pub/echo/hz/list`` and ``bag record/play/info/plot`` for rm_ros2.

The console script ``rmcli`` runs ``main``; each verb is a module with
``add_arguments(parser)`` and ``run(args)``.
"""

from .errors import BagError, CliError, MessageFieldError, MessageTypeError, UsageError
from .main import main

__all__ = ['BagError', 'CliError', 'MessageFieldError', 'MessageTypeError', 'UsageError', 'main']
