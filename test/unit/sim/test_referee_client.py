"""The simulated operator client: figures by name, and what the referee would refuse."""

import pytest
from rm_base.hardware.protocols import referee as ref
from rm_base.sim.referee_client import SimClient

MS = 1_000_000


def frame(data):
    return ref.decode_frame(ref.encode_frame(0x0301, data))


def circle(name, op=ref.FigureOp.ADD, radius=10, layer=0):
    return ref.circle(name, (100, 100), radius, op=op, layer=layer)


def test_figures_are_added_modified_and_deleted_by_name():
    client = SimClient(3)
    client.on_frame(frame(ref.draw(3, [circle(b'AAA'), circle(b'BBB', layer=2)])), 0)
    assert set(client.shown) == {b'AAA', b'BBB'}
    client.on_frame(frame(ref.draw(3, [circle(b'AAA', ref.FigureOp.MODIFY, radius=20)])), 0)
    assert client.shown[b'AAA'].figure.details_c == 20
    assert client.shown[b'AAA'].figure.op is ref.FigureOp.ADD
    client.on_frame(frame(ref.delete(3, ref.DeleteOp.LAYER, 2)), 0)
    assert set(client.shown) == {b'AAA'}
    text = ref.text_figure(b'TXT', (10, 10), 4)
    client.on_frame(frame(ref.draw_text(3, text, 'GYRO')), 0)
    assert client.shown[b'TXT'].text == 'GYRO'
    client.on_frame(frame(ref.draw(3, [circle(b'AAA', ref.FigureOp.DELETE)])), 0)
    client.on_frame(frame(ref.delete(3, ref.DeleteOp.ALL)), 0)
    assert client.shown == {} and not client.errors


def test_what_the_client_does_not_show_cannot_be_modified_or_deleted():
    client = SimClient(3)
    client.on_frame(frame(ref.draw(3, [circle(b'AAA', ref.FigureOp.MODIFY)])), 0)
    client.on_frame(frame(ref.draw(3, [circle(b'BBB', ref.FigureOp.DELETE)])), 0)
    assert client.errors == {'modify of a figure not shown': 1,
                             'delete of a figure not shown': 1}


def test_another_robots_frames_or_a_wrong_receiver_are_counted_not_shown():
    client = SimClient(3)
    client.on_frame(frame(ref.draw(4, [circle(b'AAA')])), 0)
    client.on_frame(frame(ref.interaction(0x0101, 3, 0x0104, bytes(15))), 0)
    client.on_frame(frame(ref.interaction(0x0199, 3, 0x0103, bytes(15))), 0)
    assert client.errors == {'wrong sender': 1, 'not to its client': 1, 'unknown content': 1}
    assert client.shown == {}


def test_a_reconnect_shows_nothing():
    client = SimClient(3)
    client.on_frame(frame(ref.draw(3, [circle(b'AAA')])), 0)
    client.reconnect()
    assert (client.shown, client.reconnects) == ({}, 1)


@pytest.mark.parametrize(('every_ms', 'peak_frames', 'over'), [
    (100, 10, False),  # 10 Hz x 120 B
    (25, 40, True),  # 40 Hz x 120 B = 4800 B/s
])
def test_the_rate_and_the_bandwidth_are_judged_in_every_window_of_a_second(every_ms,
                                                                            peak_frames, over):
    client = SimClient(3)
    data = ref.draw(3, [circle(b'C%02d' % i) for i in range(7)])  # 120-byte frames
    for i in range(3 * 1000 // every_ms):
        client.on_frame(frame(data), i * every_ms * MS)
    assert (client.peak_frames_per_s, client.peak_bytes_per_s) == (peak_frames,
                                                                   120 * peak_frames)
    assert set(client.errors) == ({'over 30 frames/s', 'over 3720 bytes/s'} if over else set())
