"""Manual control: the DR16 remote and the image link's keyboard and mouse as command topics."""

from rm_plugins.manual.plugin import ManualControl

__all__ = ['ManualControl']
