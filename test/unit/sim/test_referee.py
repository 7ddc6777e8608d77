"""The simulated referee on its pty: what it sends, when, and what its outputs switch."""

import time

import pytest
import serial
from rm_base.hardware.protocols import referee as ref
from rm_base.motors.dji import protocol as dji
from rm_base.sim import SimBus, SimConfigError, SimReferee, SimWorld

from .helpers import send, unique_channel

FREE = {'coulomb_friction': 0.0, 'viscous_friction': 0.0}
WHEELS = ['wheel_fl', 'wheel_fr', 'wheel_rl', 'wheel_rr']


def world_config(path, channel, **referee):
    motors = [{'type': 'm3508', 'id': i + 1, 'name': n, **FREE} for i, n in enumerate(WHEELS)]
    motors += [
        {'type': 'm3508', 'id': 5, 'name': 'friction_l', **FREE},
        {'type': 'm3508', 'id': 6, 'name': 'friction_r', **FREE},
        {'type': 'm2006', 'id': 7, 'name': 'trigger', **FREE},
        {'type': 'gm6020', 'id': 4, 'name': 'yaw', **FREE},
    ]
    return {
        'timing': 'stepped',
        'channels': {channel: motors},
        'body': {
            'chassis': {'type': 'mecanum', 'motors': WHEELS, 'wheelbase': 0.4, 'track': 0.4,
                        'wheel_radius': 0.0763},
            'gimbal': {'yaw': {'motor': 'yaw'}},
            'shooter': {'trigger': {'motor': 'trigger'},
                        'friction_motors': ['friction_l', 'friction_r'],
                        'friction_directions': [1, -1], 'slots': 8, 'fire_phase': 0.55,
                        'speed_ratio': 0.3},
        },
        'referee': {'path': path, **referee},
    }


@pytest.fixture
def path(tmp_path, monkeypatch):
    monkeypatch.setenv('RM_SIM_TEST_DIR', str(tmp_path))
    return '${RM_SIM_TEST_DIR}/dev/referee'


def read_records(port, version, seconds=5.0):
    """Every record the referee wrote so far (the frames are already in the pty)."""
    parser, decoder = ref.FrameParser(), ref.StatusDecoder(version)
    records = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        data = port.read(port.in_waiting or 1)
        if not data:
            break
        records += [decoder.decode(frame) for frame in parser.feed(data)]
    assert (parser.stats.header_errors, parser.stats.crc_errors) == (0, 0)
    return records


@pytest.mark.parametrize('version', [2024, 2025, 2026])
def test_a_second_of_reports_in_the_seasons_layouts(path, version):
    world = SimWorld.from_config(
        world_config(path, unique_channel(), protocol_version=version, robot_id=103)
    )
    with world, serial.Serial(world.referee.port.path, timeout=0.2) as port:
        world.advance(1.0)
        records = read_records(port, ref.ProtocolVersion(str(version)))
    kinds = [type(r).__name__ for r in records]
    assert kinds.count('GameStatus') == 1
    assert kinds.count('RobotStatus') == kinds.count('PowerHeat') == 10
    assert kinds.count('ProjectileAllowance') == 10
    status = next(r for r in records if isinstance(r, ref.RobotStatus))
    assert (status.robot_id, status.barrel_heat_limit, status.chassis_power_limit_w) == (
        103, 100, 60.0)
    game = records[0]
    assert (game.progress, game.stage_remaining_s) == (ref.GameProgress.IN_MATCH, 419)


def test_every_projectile_is_reported_and_heats_the_barrel(path):
    frames = []
    with SimWorld.from_config(world_config(path, unique_channel())) as world:
        world.serial_sink = lambda device, frame: frames.append((device, frame))
        world.motor('friction_l').model.reset(velocity=40.0)
        world.motor('friction_r').model.reset(velocity=-40.0)
        world.motor('trigger').model.reset(angle=0.56)  # one pocket past the firing point
        world.step()
        world.advance(0.1)
        assert world.body.launcher.shots == 1
    decoder = ref.StatusDecoder(ref.ProtocolVersion.V2026)
    records = [decoder.decode(ref.decode_frame(f)) for _, f in frames]
    assert all(isinstance(device, SimReferee) for device, _ in frames)
    (shot,) = [r for r in records if isinstance(r, ref.ShootData)]
    assert shot.speed_mps == pytest.approx(0.3 * 40.0, rel=1e-3)
    heat = next(r for r in records if isinstance(r, ref.PowerHeat))
    assert heat.heat_17mm == 9  # 10 for the shot, less the step's cooling (10/s for 0.1 s)


def test_an_empty_buffer_cuts_the_wheels_power_for_five_seconds(path):
    channel = unique_channel()
    with SimWorld.from_config(
        world_config(path, channel, chassis_power_limit=10.0, buffer_max=5.0)
    ) as world:
        bus = SimBus(channel, world=world)
        try:
            for _ in range(400):
                send(bus, 0x200, dji.pack_command([8000, 8000, 8000, 8000]))
                world.step()
            rules = world.referee.rules
            assert rules.chassis_cuts == 1
            assert [world.motor(w).powered for w in WHEELS] == [False] * 4
            assert world.motor('yaw').powered and world.motor('trigger').powered
            assert world.motor('wheel_fl').model.current == 0.0
            world.advance(5.0)
            assert all(world.motor(w).powered for w in WHEELS)
        finally:
            bus.shutdown()


def test_a_destroyed_robot_has_every_output_off_until_revived(path):
    with SimWorld.from_config(world_config(path, unique_channel(), max_hp=10)) as world:
        referee = world.referee
        for _ in range(60):  # far over twice the limit: the HP goes at the next step
            referee.rules.shot(0, 15.0)
        world.advance(0.1)
        assert referee.rules.destroyed
        assert not any(world.motor(m).powered for m in [*WHEELS, 'yaw', 'trigger'])
        with world.lock:
            referee.revive()
        assert all(world.motor(m).powered for m in [*WHEELS, 'yaw', 'trigger'])


def test_unplugged_it_sends_nothing_but_keeps_judging(path):
    with SimWorld.from_config(world_config(path, unique_channel())) as world:
        frames = []
        world.serial_sink = lambda device, frame: frames.append(frame)
        world.referee.unplug()
        world.advance(0.5)
        assert frames == [] and world.referee.rules.buffer_j == 60.0
        world.referee.plug()
        world.advance(0.1)
        assert frames


@pytest.mark.parametrize(
    ('change', 'message'),
    [({'protocol_version': 2023}, 'protocol_version'), ({'calibre': 42}, 'calibre'),
     ({'cooling': 'fast'}, 'cooling'), ({'penalties': True}, 'unknown key'),
     ({'path': None}, 'path')],
)
def test_bad_config_is_refused_naming_the_key(path, change, message):
    with pytest.raises(SimConfigError, match=message):
        SimWorld.from_config({**world_config(path, unique_channel()),
                              'referee': {'path': path, **change}})


def test_the_referee_needs_the_body_first(path):
    with SimWorld.from_config(world_config(path, unique_channel())) as world:
        with pytest.raises(Exception, match='body before the referee'):
            world.set_body({})


def test_what_the_robot_writes_on_the_terminal_reaches_its_client(path):
    world = SimWorld.from_config(world_config(path, unique_channel(), robot_id=3))
    with world, serial.Serial(world.referee.port.path, timeout=0.2) as port:
        figure = ref.circle(b'AIM', (960, 540), 40)
        port.write(ref.encode_frame(0x0301, ref.draw(3, [figure])) + b'\x00garbage')
        port.flush()
        world.step(2)
        client = world.referee.client
        assert client.shown[b'AIM'].figure == figure
        assert (client.frames, dict(client.errors)) == (1, {})
