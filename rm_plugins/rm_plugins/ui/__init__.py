"""The operator's client UI (``rm_plugins/ClientUi``): figures through the referee link."""

from rm_plugins.ui.plugin import ClientUi

__all__ = ['ClientUi']
