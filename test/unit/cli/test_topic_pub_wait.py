"""topic pub --once/--times: it waits for the subscribers, then for them to match it."""

from rm_bringup.cli import topic_pub


class _Publisher:
    def __init__(self, counts):
        self._counts = iter(counts)
        self.last = 0

    def get_subscription_count(self):
        self.last = next(self._counts, self.last)
        return self.last


class _Unheard:
    def poll(self):
        pass


def test_the_first_message_waits_for_the_subscribers_side_of_discovery_too():
    slept = []
    topic_pub._wait_for_subscriptions(_Publisher([0, 0, 1]), 1, None, _Unheard(), slept.append)
    # two polls while none matched, then the settle for the robot's side to match ours
    assert slept == [topic_pub._WAIT_POLL_S] * 2 + [topic_pub.MATCH_SETTLE_S]
    assert topic_pub.MATCH_SETTLE_S >= 0.5  # a busy robot took 0.33 s


def test_a_stream_that_waits_for_no_one_starts_at_once():
    slept = []
    topic_pub._wait_for_subscriptions(_Publisher([0]), 0, None, _Unheard(), slept.append)
    assert slept == []
