"""Auto-aim from the vision stack (``rm_plugins/AutoAim``): aim at the plate, fire on it."""

from rm_plugins.autoaim.plugin import AutoAim

__all__ = ['AutoAim']
