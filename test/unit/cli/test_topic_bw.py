"""topic bw's window: bytes per second over the window's span, sizes in ros2's units."""

from rm_bringup.cli.topic_bw import BandwidthWindow

S = 1_000_000_000


def test_the_rate_is_the_windows_bytes_over_its_span_and_old_messages_leave_it():
    window = BandwidthWindow(window_size=3)
    assert window.stats(0) is None
    for i, size in enumerate((100, 200, 300, 400)):
        window.add(i * S // 10, size)  # one every 0.1 s
    stats = window.stats(4 * S // 10)
    # the last three: 900 B from 0.1 s to 0.4 s
    assert (stats.window, stats.smallest, stats.largest, stats.mean) == (3, 200, 400, 300)
    assert stats.bytes_per_s == 3000.0
    assert stats.format() == (
        '3.00 KB/s from 3 messages\n\tMessage size mean: 300 B min: 200 B max: 400 B'
    )


def test_large_messages_are_in_megabytes():
    window = BandwidthWindow()
    window.add(0, 2_500_000)
    window.add(S, 2_500_000)
    assert window.stats(S).format().startswith('5.00 MB/s from 2 messages')
