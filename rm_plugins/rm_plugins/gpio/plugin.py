"""UpboardGpio: named GPIO inputs, outputs and PWM duty cycles over ROS topics."""

from __future__ import annotations

import collections
import re
import threading
from enum import Enum
from typing import Any

from rclpy.qos import QoSProfile
from rclpy.time import Time
from rm_base.plugin import DefaultState, PluginBase

from rm_msgs.msg import GpioCmd, GpioState
from rm_plugins.gpio.backend import GpioBackend
from rm_plugins.gpio.errors import GpioBackendError, GpioCommandError, GpioConfigError
from rm_plugins.gpio.linux_backend import LinuxGpioBackend
from rm_plugins.gpio.pins import (
    Bias,
    ConstantInput,
    DigitalLine,
    JointPhaseSwitch,
    PinKind,
    PinSpec,
    PwmChannel,
    check_command,
)
from rm_plugins.gpio.sim_backend import SimGpioBackend

COMMAND_TOPIC = 'gpio_cmd'
STATE_TOPIC = 'gpio_state'

# A GpioCmd is a one-shot setting, not a stream: losing one would leave an output wrong
# until the next, so the subscription is reliable (as `ros2 topic pub` publishes).
COMMAND_QOS = QoSProfile(depth=10)
STATE_QOS_DEPTH = 10

# Commands received between two ticks are kept (in order) up to this many.
_INBOX_SIZE = 64
_LOG_PERIOD_NS = 500_000_000  # at most two "rejected" lines a second
_PIN_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*')


class BackendKind(Enum):
    """Where the pins are."""

    SIM = 'sim'  # simulated: outputs recorded, inputs from models (SimGpioBackend)
    LINUX = 'linux'  # GPIO character device (gpiod) + sysfs PWM (LinuxGpioBackend)


class SimModel(Enum):
    """How the simulated backend plays an input."""

    CONSTANT = 'constant'  # always sim_value
    JOINT_PHASE = 'joint_phase'  # closed while sim_joint's phase is inside sim_window


class UpboardGpio(PluginBase):
    """Named GPIO pins of the robot's computer (an UP board, or any Linux GPIO).

    Topics:
        gpio_cmd (rm_msgs/GpioCmd, in): set outputs (0/1) and PWM duty cycles ([0, 1]) by
            name. A command is checked as a whole; an unknown name, an input pin, a value
            out of range or NaN rejects it (logged) and nothing of it is applied.
        gpio_state (rm_msgs/GpioState, out): every pin's kind and value, each tick.

    Parameters (under ``<name>.``):
        backend: ``sim`` or ``linux`` (required).
        chip: default GPIO character device of digital pins (``/dev/gpiochip0``).
        inputs, outputs, pwm_outputs: pin names of each kind (names are unique).
        pins.<pin>.line: line offset on the chip (linux; -1 = not wired).
        pins.<pin>.chip: chip of that line (default ``chip``).
        pins.<pin>.active_low: the pin reads/writes 1 when low (default false).
        pins.<pin>.bias: as_is, disabled, pull_up or pull_down (default as_is).
        pins.<pin>.initial: output/PWM value at start-up and after disable (default 0).
        pins.<pin>.pwm_chip, pins.<pin>.pwm_channel: sysfs PWM channel (linux PWM pins).
        pins.<pin>.frequency: PWM frequency [Hz] (PWM pins, required).
        pins.<pin>.sim_model: ``constant`` (default) or ``joint_phase`` (inputs, sim).
        pins.<pin>.sim_value: value of a constant simulated input (0 or 1, default 0).
        pins.<pin>.sim_joint, sim_slots, sim_window: the ``joint_phase`` model (see
            ``JointPhaseSwitch``): the joint [from /actuator_states, not claimed], pockets
            per turn, and the phase window [rad] in which the switch is closed.

    States: PASSIVE (disabled: outputs at their initial values), ACTIVE.
    """

    def on_init(self) -> None:
        """Read the pins, open the backend, set up the topics."""
        backend_kind = self.params.choice(
            'backend', BackendKind, description='where the pins are: sim or linux'
        )
        self.pins = self._read_pins()
        self.backend = self._open_backend(backend_kind)
        self._order = list(self.pins)
        self._inbox: collections.deque[GpioCmd] = collections.deque(maxlen=_INBOX_SIZE)
        self._inbox_lock = threading.Lock()
        self._overflowed = 0
        self._next_log_ns = 0
        self._suppressed = 0
        # a new message each run: the shooter (ball switch) gets it with no copy
        self.state_pub = self.create_publisher(
            GpioState, STATE_TOPIC, STATE_QOS_DEPTH, hand_over=True
        )
        self.subscribe(COMMAND_TOPIC, GpioCmd, self._on_command, COMMAND_QOS)
        self.logger.info(
            f'{backend_kind.value} backend: '
            + ', '.join(f'{name} ({spec.kind.name.lower()})' for name, spec in self.pins.items())
        )

    # -- hooks --------------------------------------------------------------------------------

    def update(self, now: Time, dt: float) -> None:
        """Apply the commands received since the last tick, then publish every pin."""
        self.transition(DefaultState.ACTIVE, f'{len(self.pins)} pin(s) on the backend')
        for msg in self._take_commands():
            self._apply(msg, now.nanoseconds)
        if self.heard(self.state_pub):
            self.state_pub.publish(self._state_message(now))

    def on_disable(self) -> None:
        """Put the outputs back to their initial (safe) values."""
        self.backend.reset_outputs()

    # -- commands -----------------------------------------------------------------------------

    def _on_command(self, msg: GpioCmd, receive_ns: int) -> None:
        # Executor thread: only hand the message over.
        with self._inbox_lock:
            if len(self._inbox) == self._inbox.maxlen:
                self._overflowed += 1
            self._inbox.append(msg)

    def _take_commands(self) -> list[GpioCmd]:
        with self._inbox_lock:
            messages = list(self._inbox)
            self._inbox.clear()
            overflowed, self._overflowed = self._overflowed, 0
        if overflowed:
            self.logger.warning(
                f'{overflowed} /gpio_cmd message(s) dropped: more than {_INBOX_SIZE} in one tick'
            )
        return messages

    def _apply(self, msg: GpioCmd, now_ns: int) -> None:
        try:
            writes = check_command(self.pins, list(msg.name), list(msg.value))
        except GpioCommandError as err:
            self._log_rejected(str(err), now_ns)
            return
        for name, value in writes.items():
            self.backend.write(name, value)

    def _log_rejected(self, text: str, now_ns: int) -> None:
        if now_ns < self._next_log_ns:
            self._suppressed += 1
            return
        more = (
            f' ({self._suppressed} more rejected since the last report)' if self._suppressed else ''
        )
        self._suppressed = 0
        self._next_log_ns = now_ns + _LOG_PERIOD_NS
        self.logger.warning(text + more)

    def _state_message(self, now: Time) -> GpioState:
        msg = GpioState()
        msg.header.stamp = now.to_msg()
        msg.name = self._order
        msg.kind = [int(self.pins[name].kind) for name in self._order]
        msg.value = [float(self.backend.read(name)) for name in self._order]
        return msg

    # -- set-up -------------------------------------------------------------------------------

    def _read_pins(self) -> dict[str, PinSpec]:
        params = self.params
        default_chip = params.string(
            'chip', '/dev/gpiochip0', description='default GPIO character device of the pins'
        )
        kinds = {
            PinKind.INPUT: params.string_array(
                'inputs', [], description='names of the digital input pins', unique=True
            ),
            PinKind.OUTPUT: params.string_array(
                'outputs', [], description='names of the digital output pins', unique=True
            ),
            PinKind.PWM: params.string_array(
                'pwm_outputs', [], description='names of the PWM output pins', unique=True
            ),
        }
        seen: dict[str, PinKind] = {}
        for kind, names in kinds.items():
            for name in names:
                if not _PIN_NAME.fullmatch(name):
                    raise GpioConfigError(
                        f'pin name {name!r} is not valid (a letter, then letters, digits or _)'
                    )
                if name in seen:
                    raise GpioConfigError(
                        f'pin {name!r} is listed as {seen[name].name.lower()} and as '
                        f'{kind.name.lower()}'
                    )
                seen[name] = kind
        if not seen:
            raise GpioConfigError('no pins: set inputs, outputs and/or pwm_outputs')
        return {name: self._read_pin(name, kind, default_chip) for name, kind in seen.items()}

    def _read_pin(self, name: str, kind: PinKind, default_chip: str) -> PinSpec:
        params = self.params
        key = f'pins.{name}.'
        line = None
        pwm = None
        sim: Any = ConstantInput()
        if kind is PinKind.PWM:
            initial = params.double(
                key + 'initial',
                0.0,
                description='duty cycle at start-up and after disable',
                ge=0.0,
                le=1.0,
            )
            chip = params.integer(
                key + 'pwm_chip', -1, description='sysfs PWM chip number (-1: not wired)', ge=-1
            )
            channel = params.integer(
                key + 'pwm_channel', -1, description='sysfs PWM channel (-1: not wired)', ge=-1
            )
            frequency = params.double(
                key + 'frequency', description='PWM frequency', unit='Hz', gt=0.0
            )
            if chip >= 0 and channel >= 0:
                pwm = PwmChannel(chip, channel, frequency)
        else:
            offset = params.integer(
                key + 'line', -1, description='line offset on the chip (-1: not wired)', ge=-1
            )
            chip_path = params.string(key + 'chip', default_chip, description='GPIO chip')
            active_low = params.boolean(
                key + 'active_low', False, description='the pin is active (1) when low'
            )
            bias = params.choice(key + 'bias', Bias, Bias.AS_IS, description='internal bias')
            if offset >= 0:
                line = DigitalLine(chip_path, offset, active_low, bias)
            if kind is PinKind.OUTPUT:
                initial = float(
                    params.integer(
                        key + 'initial',
                        0,
                        description='value at start-up and after disable',
                        ge=0,
                        le=1,
                    )
                )
            else:
                initial = 0.0
                sim = self._read_sim_input(key)
        return PinSpec(name, kind, initial, line=line, pwm=pwm, sim=sim)

    def _read_sim_input(self, key: str) -> ConstantInput | JointPhaseSwitch:
        params = self.params
        model = params.choice(
            key + 'sim_model',
            SimModel,
            SimModel.CONSTANT,
            description='simulated input model: constant or joint_phase',
        )
        if model is SimModel.CONSTANT:
            value = params.integer(
                key + 'sim_value', 0, description='value of the simulated input', ge=0, le=1
            )
            return ConstantInput(float(value))
        joint = params.string(
            key + 'sim_joint', description='joint whose phase closes the simulated switch'
        )
        slots = params.integer(
            key + 'sim_slots', description='pockets per turn of that joint', ge=1
        )
        window = params.double_array(
            key + 'sim_window',
            description='phase window in which the switch is closed',
            unit='rad',
            length=2,
            ge=0.0,
        )
        return JointPhaseSwitch(joint, slots, (window[0], window[1]))

    def _open_backend(self, kind: BackendKind) -> GpioBackend:
        if kind is BackendKind.SIM:
            return SimGpioBackend(self.pins, self._joint_position)
        try:
            return LinuxGpioBackend(self.pins, consumer=f'rm_robot/{self.name}')
        except GpioBackendError as err:
            raise GpioBackendError(f'{kind.value} backend: {err}') from err

    def _joint_position(self, joint: str) -> float | None:
        state = self.joint_states.get(joint)
        return None if state is None else state.position
