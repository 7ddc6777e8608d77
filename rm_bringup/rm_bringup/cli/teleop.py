"""``rmcli teleop``: drive the robot from the terminal's keyboard, as the operator's remote does.

    rmcli teleop --sim      # through rm_sim's DR16 receiver: rm_manual's mapping drives
    rmcli teleop            # straight onto /chassis_cmd, /vel_cmd, /gimbal_cmd, /shoot_cmd

The keys held (:mod:`.teleop_keys`) become one DR16 frame: the right switch up (keyboard
and mouse drive) or, after P, down (everything PASSIVE), the letters as its keyboard, Q/E
and the arrows as its mouse, space as the left button. With ``--sim`` the frame goes to
rm_sim's receiver (``/rm_sim/remote``), which sends it to the robot every 14 ms, and the
robot's rm_manual turns it into commands by its mapping. Without, the same mapping (the
default, or ``--mapping``) runs here and its commands go out on the plain command topics,
the ``external`` command source. Either way the screen shows the frame and the commands it
makes, and Ctrl-C ends with everything PASSIVE.
"""

from __future__ import annotations

import argparse
import os
import select
import sys
import termios
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from rm_base.hardware.protocols.dbus import DbusFrame, Key, Switch
from rm_plugins.manual.driver import Commands, ManualDriver, OperatorInput, command_messages
from rm_plugins.manual.mapping import ManualMapping, MappingError, load_mapping

from .errors import CliError
from .message_yaml import message_constants
from .options import positive_float
from .ros_node import cli_node, wait_until_heard
from .teleop_keys import Hands, TerminalKeys

#: rm_sim's receiver input (rm_base.bridge.sim_remote); can_bridge's in-process sim has
#: /can_bridge/sim/remote.
SIM_REMOTE_TOPIC = '/rm_sim/remote'
#: How long Ctrl-C keeps sending PASSIVE before leaving [s] (several of rm_manual's frames).
_STOP_S = 0.3
# How long teleop waits for its frames' subscriber before it takes keys anyway [s].
_HEARD_WAIT_S = 15.0
_COMMAND_TOPICS = ('chassis_cmd', 'vel_cmd', 'gimbal_cmd', 'shoot_cmd')


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``teleop``."""
    parser.add_argument(
        '--sim', nargs='?', const=SIM_REMOTE_TOPIC, metavar='TOPIC',
        help=f"send the DR16 frame to the simulator's receiver (default {SIM_REMOTE_TOPIC}) "
        'instead of commands to the command topics',
    )
    parser.add_argument(
        '--mapping', metavar='FILE', default='',
        help="the manual-control mapping (rm_manual's manual.mapping_file; default: "
        'rm_plugins/manual/default_mapping.yaml)',
    )
    parser.add_argument('-r', '--rate', metavar='HZ', type=positive_float, default=50.0,
                        help='how often to send [Hz] (default: 50)')


def frame_of(hands: Hands, mapping: ManualMapping) -> DbusFrame:
    """The DR16 frame of what the hands hold: the right switch as the mapping names it."""
    right = Switch.DOWN if hands.passive else Switch.UP
    a, b = (right, Switch.MID) if mapping.right_switch == 'switch_a' else (Switch.MID, right)
    return DbusFrame(switch_a=a, switch_b=b, mouse=(hands.mouse_x, hands.mouse_y, 0),
                     mouse_left=hands.mouse_left, keys=hands.keys)


def remote_message(frame: DbusFrame) -> Any:
    """The rm_msgs/RemoteInput of a frame."""
    from rm_msgs.msg import RemoteInput

    return RemoteInput(
        channels=list(frame.channels), switch_a=int(frame.switch_a),
        switch_b=int(frame.switch_b), mouse_x=frame.mouse[0], mouse_y=frame.mouse[1],
        mouse_z=frame.mouse[2], mouse_left=frame.mouse_left, mouse_right=frame.mouse_right,
        keys=frame.keys, wheel=frame.wheel,
    )


def describe(frame: DbusFrame, mapping: ManualMapping, c: Commands) -> str:
    """One screen line: the frame, then the commands the mapping makes of it."""
    from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

    right = Switch(getattr(frame, mapping.right_switch)).name
    keys = '+'.join(k.name or '' for k in Key if frame.keys & k) or '-'
    mouse = f'mouse {frame.mouse[0]:+d},{frame.mouse[1]:+d}'
    button = ' left' if frame.mouse_left else ''
    chassis = _names(ChassisCmd, exclude='GEAR_')[c.chassis_mode]
    gear = {v: k.removeprefix('GEAR_') for k, v in message_constants(ChassisCmd).items()
            if k.startswith('GEAR_')}[c.speed_gear]
    gimbal = _names(GimbalCmd)[c.gimbal_mode]
    shooter = _names(ShootCmd)[c.shoot_mode]
    vx, vy, yaw, pitch = (v + 0.0 for v in (c.vx, c.vy, c.yaw_rate, c.pitch_rate))  # no -0.0
    return (f'right {right} keys {keys} {mouse}{button} -> chassis {chassis} {gear} '
            f'v {vx:+.1f} {vy:+.1f} | gimbal {gimbal} yaw {yaw:+.1f} pitch {pitch:+.1f} | '
            f'shooter {shooter}')


def _names(msg_class: type, exclude: str = '\0') -> dict[int, str]:
    return {v: k for k, v in message_constants(msg_class).items() if not k.startswith(exclude)}


@contextmanager
def keyboard_terminal(fd: int) -> Iterator[None]:
    """The terminal of fd, key by key without echo (Ctrl-C still interrupts), restored after."""
    before = termios.tcgetattr(fd)
    after = termios.tcgetattr(fd)
    after[0] &= ~(termios.IXON | termios.ICRNL)  # Ctrl-S / Ctrl-Q are keys, not flow control
    after[3] &= ~(termios.ICANON | termios.ECHO | termios.IEXTEN)
    after[6][termios.VMIN], after[6][termios.VTIME] = 0, 0
    termios.tcsetattr(fd, termios.TCSADRAIN, after)
    try:
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, before)


def run(args: argparse.Namespace) -> int:
    """Read the keyboard and send until Ctrl-C."""
    fd = sys.stdin.fileno()
    if not os.isatty(fd):
        raise CliError('teleop reads the keyboard: run it in a terminal (stdin is not a tty)')
    try:
        mapping = load_mapping(args.mapping or None)
    except MappingError as err:
        raise CliError(str(err)) from None
    with cli_node('teleop') as node:
        send, publishers = _sender(node, args.sim)
        target = args.sim or ', '.join(f'/{t}' for t in _COMMAND_TOPICS)
        print(f'teleop -> {target}: waiting for its subscriber\r', flush=True)
        # Keys pressed before discovery matched would be published to no one.
        if not wait_until_heard(publishers, _HEARD_WAIT_S):
            print(f'nobody subscribes {target} yet (is the robot running?): '
                  'keys are sent anyway\r', flush=True)
        print('W A S D move, SHIFT (capitals) / CTRL gears, Q E and arrows are the mouse, '
              'space fires,\r\nR friction, F GYRO, G TWIST, P PASSIVE on/off, Ctrl-C quits\r',
              flush=True)
        with keyboard_terminal(fd):
            _drive(fd, mapping, send, 1.0 / args.rate, node)
    return 0


def _sender(
    node: Any, sim_topic: str | None
) -> tuple[Callable[[DbusFrame, Commands], None], list[Any]]:
    """What sends one frame's worth, and the publishers it sends with.

    The frame goes to rm_sim's receiver, or the commands to their topics.
    """
    from geometry_msgs.msg import Twist
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from rm_msgs.msg import ChassisCmd, GimbalCmd, RemoteInput, ShootCmd

    if sim_topic is not None:
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        remote = node.create_publisher(RemoteInput, sim_topic, qos)
        return (lambda frame, _c: remote.publish(remote_message(frame))), [remote]
    types = dict(zip(_COMMAND_TOPICS, (ChassisCmd, Twist, GimbalCmd, ShootCmd), strict=True))
    publishers = {t: node.create_publisher(types[t], f'/{t}', 10) for t in _COMMAND_TOPICS}

    def publish(_frame: DbusFrame, c: Commands) -> None:
        stamp = node.get_clock().now().to_msg()
        for topic, msg in command_messages(c, stamp).items():
            publishers[topic].publish(msg)

    return publish, list(publishers.values())


def _drive(fd: int, mapping: ManualMapping, send: Callable[[DbusFrame, Commands], None],
           period: float, node: Any) -> None:
    keys, driver = TerminalKeys(), ManualDriver(mapping)
    shown = ''
    next_send = time.monotonic()
    try:
        while node.context.ok():
            now = time.monotonic()
            ready, _, _ = select.select([fd], [], [], max(0.0, next_send - now))
            if ready:
                keys.feed(os.read(fd, 256), time.monotonic())
            now = time.monotonic()
            if now < next_send:
                continue
            next_send = max(next_send + period, now)
            hands = keys.hands(now)
            frame = frame_of(hands, mapping)
            commands = driver.commands(OperatorInput.from_dbus(frame, mapping))
            send(frame, commands)
            line = describe(frame, mapping, commands)
            if line != shown:  # the screen shows what goes out, rewritten in place
                print(f'\r{line}\x1b[K', end='', flush=True)
                shown = line
    except KeyboardInterrupt:
        pass
    stop = frame_of(Hands(passive=True), mapping)
    commands = driver.commands(OperatorInput.from_dbus(stop, mapping))
    print(f'\r\n{describe(stop, mapping, commands)}\r', flush=True)
    end = time.monotonic() + _STOP_S
    while time.monotonic() < end:
        send(stop, commands)
        time.sleep(period)
