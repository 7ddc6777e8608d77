"""The simulated image link: silent until switched on (a client), then 0x0304 at 30 Hz."""

import pytest
from rm_base.hardware.protocols import referee as ref
from rm_base.sim import SimConfigError, SimWorld

from .helpers import unique_channel


@pytest.fixture
def world(tmp_path):
    config = {'timing': 'stepped', 'channels': {unique_channel(): []},
              'image_link': {'path': str(tmp_path / 'image_link')}}
    with SimWorld.from_config(config) as w:
        yield w


def test_it_sends_what_the_operator_does_30_times_a_second_once_connected(world):
    frames = []
    world.serial_sink = lambda device, frame: frames.append(frame)
    world.advance(0.5)
    assert frames == []
    held = world.image_link.hold(mouse_x=-12, keys=0x0221, left=True)
    world.image_link.switch_on()
    world.advance(1.0)
    assert len(frames) == 30
    parser, decoder = ref.FrameParser(), ref.StatusDecoder(ref.ProtocolVersion.V2025)
    records = [decoder.decode(f) for f in parser.feed(b''.join(frames))]
    assert set(records) == {held}
    world.image_link.switch_off()
    world.advance(0.5)
    assert len(frames) == 30


def test_a_value_the_frame_cannot_carry_is_refused(world):
    with pytest.raises(SimConfigError, match='image_link'):
        world.image_link.hold(keys=0x10000)
    assert world.image_link.state.keys == 0
