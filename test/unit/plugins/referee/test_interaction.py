"""The referee link's 0x0301 pacing: never more bytes or frames a second than allowed."""

import pytest
from rm_base.errors import InputRejectedError
from rm_base.hardware.protocols import referee as ref
from rm_base.hardware.protocols.referee.client_ui import FRAME_OVERHEAD
from rm_plugins.referee.interaction import InteractionLink

MS = 1_000_000
SEVEN = ref.drawing([ref.circle(b'C%02d' % i, (100, 100), 5) for i in range(7)])  # 120 B frames


def run(link, robot_id, seconds, offer_every_ms=1):
    """Offer a 7-figure drawing every offer_every_ms and take each ms; the frames sent."""
    sent = []
    for ms in range(round(seconds * 1000)):
        if ms % offer_every_ms == 0 and link.waiting < 2:
            link.offer(*SEVEN[:1], 0, SEVEN[1])
        frame = link.take(robot_id, ms * MS)
        if frame is not None:
            sent.append((ms, frame))
    return sent


def windows(sent, window_ms=1000):
    """The most frames and bytes in any window of window_ms."""
    most_frames = most_bytes = 0
    for i, (start, _) in enumerate(sent):
        inside = [f for t, f in sent[i:] if t < start + window_ms]
        most_frames = max(most_frames, len(inside))
        most_bytes = max(most_bytes, sum(map(len, inside)))
    return most_frames, most_bytes


@pytest.mark.parametrize(('bytes_per_s', 'max_hz', 'frames'), [
    (3720.0, 10.0, 10),  # the rate binds: 10 x 120 B
    (3720.0, 30.0, 30),  # 3720 / 120 = 31 frames' bytes, but 30 Hz
    (2000.0, 30.0, 16),  # the bandwidth binds: 16 x 120 = 1920 B
    (3720.0, 40.0, 31),
])
def test_no_window_of_a_second_holds_more_than_either_limit(bytes_per_s, max_hz, frames):
    link = InteractionLink(bytes_per_s, max_hz)
    sent = run(link, 3, 5.0)
    assert all(len(f) == 120 for _, f in sent)
    most_frames, most_bytes = windows(sent)
    assert most_frames <= max_hz and most_bytes <= bytes_per_s
    assert most_frames == frames  # and the link uses what it is given


def test_a_frame_is_the_robots_own_0x0301_to_its_client():
    link = InteractionLink()
    content_id, content = ref.deletion(ref.DeleteOp.ALL)
    link.offer(content_id, 0, content)
    frame = link.take(103, 0)
    assert link.take(103, 99 * MS) is None  # 10 Hz
    raw = ref.decode_frame(frame)
    assert raw.cmd_id == 0x0301
    assert ref.decode_interaction(raw.data) == ref.Interaction(0x0100, 103, 0x0167, bytes((2, 0)))
    assert len(frame) == FRAME_OVERHEAD + 6 + 2
    assert (link.stats.sent, link.stats.bytes_sent) == (1, len(frame))


def test_without_the_robots_id_frames_wait_and_a_full_queue_drops_the_oldest_counted():
    link = InteractionLink(queue=2)
    for i in range(3):
        link.offer(0x0200 + i, 0, b'x')
    assert link.take(None, 0) is None
    assert (link.waiting, link.stats.dropped) == (2, 1)
    first = ref.decode_interaction(ref.decode_frame(link.take(3, 0)).data)
    assert first.content_id == 0x0201  # 0x0200 was pushed out


def test_content_too_long_is_refused_and_counted():
    link = InteractionLink()
    with pytest.raises(InputRejectedError, match='113 bytes'):
        link.offer(0x0200, 0, bytes(113))
    assert (link.stats.refused, link.waiting) == (1, 0)
