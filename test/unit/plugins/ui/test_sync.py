"""The client UI: its layout, and the frames that keep a simulated client showing it."""

from dataclasses import replace

from rm_base.hardware.protocols import referee as ref
from rm_base.sim.referee_client import SimClient
from rm_plugins.ui.layout import BAR_STEP, UiInputs, layout
from rm_plugins.ui.sync import UiSync

MS = 1_000_000
INPUTS = UiInputs(chassis='GYRO', power_limit_w=60.0, shooter='READY', friction_ready=True,
                  cap_energy=0.8, cap_state='ready', heat=30.0, heat_limit=100.0)


class Rig:
    """A UiSync sending to a SimClient, one frame per 100 ms."""

    def __init__(self, refresh_s=5.0):
        self.sync, self.client, self.t_ns, self.sent = UiSync(refresh_s), SimClient(3), 0, []

    def run(self, wanted, frames):
        for _ in range(frames):
            frame = self.sync.next_frame(wanted, self.t_ns)
            if frame is not None:
                data = ref.interaction(frame[0], 3, ref.client_id(3), frame[1])
                self.client.on_frame(ref.decode_frame(ref.encode_frame(0x0301, data)), self.t_ns)
                self.sent.append(ref.decode_interaction(data))
            self.t_ns += 100 * MS

    def showing(self, wanted):
        return {n: (s.figure, s.text) for n, s in self.client.shown.items()} == {
            n: (replace(f, op=ref.FigureOp.ADD), t) for n, (f, t) in wanted.items()}


def test_the_client_is_cleared_then_shows_every_figure_in_a_few_frames():
    rig, wanted = Rig(), layout(INPUTS)
    rig.run(wanted, 5)
    assert rig.sent[0].content_id == 0x0100  # delete everything first
    assert rig.showing(wanted) and not rig.client.errors
    assert len(rig.sent) == 5  # 1 clear, 2 of graphics (11 figures), 2 texts
    rig.run(wanted, 10)
    assert len(rig.sent) == 5  # nothing changed: nothing sent


def test_a_change_modifies_only_the_figures_it_changes():
    rig = Rig()
    rig.run(layout(INPUTS), 5)
    wanted = layout(replace(INPUTS, cap_energy=0.5))
    rig.run(wanted, 3)
    (frame,) = rig.sent[5:]
    figures, _ = ref.decode_drawing(frame.content_id, frame.content)
    assert {f.name for f in figures} == {b'CPB', b'CPN'}
    assert {f.op for f in figures} == {ref.FigureOp.MODIFY}
    assert rig.showing(wanted) and not rig.client.errors


def test_noise_smaller_than_a_step_sends_nothing():
    rig = Rig()
    rig.run(layout(INPUTS), 5)
    small = (BAR_STEP / 400) * 0.4
    rig.run(layout(replace(INPUTS, heat=30.0 + 100.0 * small)), 3)
    assert len(rig.sent) == 5


def test_a_figure_no_longer_wanted_is_deleted():
    rig = Rig()
    rig.run(layout(INPUTS), 5)
    wanted = layout(replace(INPUTS, cap_state=None))  # the capacitor gone from the config
    rig.run(wanted, 3)
    figures, _ = ref.decode_drawing(rig.sent[5].content_id, rig.sent[5].content)
    assert {(f.name, f.op) for f in figures} == {
        (n, ref.FigureOp.DELETE) for n in (b'CPO', b'CPB', b'CPN')}
    assert rig.showing(wanted) and not rig.client.errors


def test_texts_and_graphics_take_turns():
    rig = Rig()
    rig.run(layout(INPUTS), 1)  # the clear
    rig.run(layout(INPUTS), 4)
    # from the start: 11 graphics (two frames) and two texts wait
    assert [s.content_id == 0x0110 for s in rig.sent[1:]] == [False, True, False, True]
    rig.run(layout(replace(INPUTS, chassis='RAW', heat=90.0, friction_ready=False)), 6)
    assert [s.content_id == 0x0110 for s in rig.sent[5:]] == [False, True, True]


def test_a_restarted_client_is_drawn_again_within_the_refresh_period():
    rig, wanted = Rig(refresh_s=2.0), layout(INPUTS)
    rig.run(wanted, 5)
    rig.client.reconnect()
    rig.run(wanted, 20 + 4)  # the refresh period, then its four frames
    assert rig.showing(wanted) and not rig.client.errors


def test_resend_clears_and_draws_everything_at_once():
    rig, wanted = Rig(refresh_s=60.0), layout(INPUTS)
    rig.run(wanted, 5)
    rig.client.reconnect()
    rig.sync.resend()
    rig.run(wanted, 5)
    assert rig.showing(wanted) and not rig.client.errors
    assert rig.sent[5].content_id == 0x0100


def test_the_chassis_text_says_its_mode_gear_and_power_limit():
    items = layout(replace(INPUTS, gear='FAST', power_limit_w=160.0))
    assert items[b'CMD'][1] == 'GYRO FAST 160W'
    assert layout(replace(INPUTS, gear='NORMAL'))[b'CMD'][1] == 'GYRO 60W'
