"""The simulated DR16 receiver: silent until switched on, then what the operator holds."""

import pytest
import serial
from rm_base.hardware.protocols import dbus
from rm_base.sim import SimConfigError, SimWorld

from .helpers import unique_channel


@pytest.fixture
def world(tmp_path):
    config = {'timing': 'stepped', 'channels': {unique_channel(): []},
              'remote': {'path': str(tmp_path / 'dr16')}}
    with SimWorld.from_config(config) as w:
        yield w


def test_it_is_silent_until_switched_on_then_sends_a_frame_every_14_ms(world):
    frames = []
    world.serial_sink = lambda device, frame: frames.append(frame)
    world.advance(0.5)
    assert frames == []
    world.remote.switch_on()
    world.advance(0.14)
    assert len(frames) == 10
    assert {dbus.decode(f) for f in frames} == {dbus.DbusFrame()}
    world.remote.switch_off()
    world.advance(0.1)
    assert len(frames) == 10


def test_what_the_operator_holds_is_what_the_frames_carry_through_the_pty(world):
    remote = world.remote
    held = remote.hold(channels=(660, -330, 0, 12), switch_a=dbus.Switch.UP,
                       keys=int(dbus.Key.W | dbus.Key.SHIFT), mouse=(5, -7, 0), mouse_left=True)
    remote.switch_on()
    with serial.Serial(remote.port.path, timeout=0.5) as port:
        world.step()
        assert dbus.decode(port.read(dbus.FRAME_LENGTH)) == held


def test_a_stick_the_dr16_cannot_send_is_refused_and_the_old_state_kept(world):
    with pytest.raises(SimConfigError, match='±660'):
        world.remote.hold(channels=(700, 0, 0, 0))
    assert world.remote.state == dbus.DbusFrame()


def test_bad_config_is_refused(tmp_path):
    with pytest.raises(SimConfigError, match='unknown key'):
        SimWorld.from_config({'timing': 'stepped', 'remote': {'path': 'x', 'baud': 1}})
    with pytest.raises(SimConfigError, match='path'):
        SimWorld.from_config({'timing': 'stepped', 'remote': {}})
