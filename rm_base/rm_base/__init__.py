"""rm_base: the rm_ros2 framework (plugins, host, control maths, CAN layer, bridge, simulator)."""

from rm_base.runtime import compiled as _compiled

# Before any module of the compiled group is imported: compiled, or all from source.
_compiled.choose()
