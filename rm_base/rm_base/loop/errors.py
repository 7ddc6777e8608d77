"""The loop's error: a composition it cannot run (a bad rate, a cycle, an unread output)."""

from rm_base.errors import ConfigError


class LoopConfigError(ConfigError):
    """The loop's settings or components do not make a loop; the message names them."""
