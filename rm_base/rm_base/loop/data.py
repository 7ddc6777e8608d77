"""The names of the data the loop's components read and write (rm_base.loop.order).

A datum is a name, not a buffer: the components share their objects (the actuators, the
plugins' joint view) as before; the names only say who needs whose work first.
"""

JOINT_STATES = 'joint states'
"""What the motors last reported (the feedback stage writes it)."""

JOINT_TARGETS = 'joint targets'
"""The joints' setpoints (plugins, or the bridge's /actuator_cmd, write them)."""

JOINT_GAINS = 'joint gains'
"""The joints' loop gains (set while running, between two ticks)."""

JOINT_EFFORTS = 'joint efforts'
"""The actuators' outputs this tick (their update writes them; power limits scale them)."""

FRAMES = 'frames'
"""The packed CAN frames of this tick (pack writes them; send reads them)."""

COMMANDS = 'commands'
"""The command messages taken for the plugins this tick (the inbox writes them)."""

PUBLISHED = 'published'
"""What the loop hands the ROS edge to publish (states, diagnostics)."""


def port(name: str) -> str:
    """What a plugin's device sent (its serial port read in the loop)."""
    return f'port {name}'
