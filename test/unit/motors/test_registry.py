"""The motor family registry: built-in families, and a third-party one from an entry point."""

import textwrap

import pytest
from rm_base.bridge.sim_config import motor_config
from rm_base.hardware import MODE_MIT, CanHardware
from rm_base.hardware.errors import HardwareConfigError
from rm_base.motors import MotorFamily, MotorFamilyError, UnknownTypeError
from rm_base.motors.cheetah.actuator import Cheetah
from rm_base.motors.dji.actuator import M3508, Gm6020Voltage
from rm_base.sim.world import SimWorld
from rm_base.sim_devices.errors import SimConfigError
from support.hardware import FakeClock, joint, sim_factory, wait_fresh

from rm_base import motors

# A motor family of its own package, as a team would ship it: an MIT-protocol joint type
# and its simulated motor, registered through the rm_base.motor_families entry point.
ACME_MODULE = """
from rm_base.config.schema import Schema, integer
from rm_base.motors import MotorFamily, SimFamily
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.cheetah.actuator import Cheetah
from rm_base.motors.cheetah.sim_device import CheetahDevice
from rm_base.sim import MOTOR_DEFAULTS, MotorType


class AcmeJoint(Cheetah):
    type_name = 'acme_mit'


def build(cfg, parts):
    return CheetahDevice(
        parts.name, parts.sim_type, parts.motor_id, parts.model,
        cheetah.CHEETAH_DEFAULT_LIMITS, master_id=cfg['master_id'], **parts.common,
    )


FAMILY = MotorFamily(
    name='acme',
    actuators=(AcmeJoint,),
    sim=SimFamily(
        models={'acme_sim': MOTOR_DEFAULTS[MotorType.CHEETAH].replace(load_inertia=1e-4)},
        schema=Schema((integer('master_id', 0, description='replies'),)),
        build=build,
        joint_types={'acme_mit': ('acme_sim', {})},
        shared_options=('master_id',),
    ),
)
NOT_A_FAMILY = 42
"""


def install(tmp_path, monkeypatch, entry_points):
    """Put the acme package and its distribution metadata on sys.path."""
    (tmp_path / 'acme_motors.py').write_text(ACME_MODULE)
    info = tmp_path / 'acme_motors-1.0.dist-info'
    info.mkdir()
    (info / 'METADATA').write_text('Metadata-Version: 2.1\nName: acme-motors\nVersion: 1.0\n')
    (info / 'entry_points.txt').write_text(
        '[rm_base.motor_families]\n' + textwrap.dedent(entry_points)
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    motors.reload()


@pytest.fixture(autouse=True)
def forget_families():
    yield
    motors.reload()  # the next test sees the built-in families only


def test_every_built_in_joint_type_finds_its_class_and_family():
    assert list(motors.families()) == ['dji', 'damiao', 'cheetah', 'piper', 'lk']
    for name, family in motors.families().items():
        for cls in family.actuators:
            assert motors.actuator_class(cls.type_name) is cls
            assert motors.family_of(cls.type_name).name == name
    assert motors.actuator_class('m3508') is M3508
    assert motors.actuator_class('gm6020') is Gm6020Voltage
    assert motors.family_of('dm4340').sim.simulated_type(joint(type='dm4340')) == (
        'dm4310', {'model': 'DM4340'}
    )
    assert motors.families()['piper'].sim is None  # no simulated arm
    assert motors.family_of('lk').sim.simulated_type(
        joint(type='lk', current_scale='mg')) == ('mg4010', {})


@pytest.mark.parametrize('bad', ['m3509', '', 3, None])
def test_an_unknown_joint_type_is_refused_with_the_known_ones(bad):
    with pytest.raises(UnknownTypeError, match=f'type {bad!r} is unknown; known: cheetah, '):
        motors.actuator_class(bad)
    with pytest.raises(UnknownTypeError, match=f'unknown motor type {bad!r}'):
        motors.sim_family(bad)


def test_a_family_from_an_entry_point_drives_its_simulated_motor(tmp_path, monkeypatch, channel):
    install(tmp_path, monkeypatch, 'acme = acme_motors:FAMILY\n')
    assert list(motors.families()) == ['dji', 'damiao', 'cheetah', 'piper', 'lk', 'acme']
    acme_class = motors.actuator_class('acme_mit')
    assert issubclass(acme_class, Cheetah) and acme_class.__module__ == 'acme_motors'

    # the bridge's sim config and the simulator build its motor, the hardware drives it
    config = motor_config(joint('arm', type='acme_mit', id=3, master_id=0))
    assert config == {'type': 'acme_sim', 'id': 3, 'name': 'arm', 'master_id': 0}
    world = SimWorld(timing='stepped')
    world.add_channel(channel, [config])
    clock = FakeClock()
    hw = CanHardware(
        {
            'buses': {'can0': {'interface': 'rm_sim', 'channel': channel,
                               'options': {'world': world}, 'receive_timeout_s': 0.01}},
            'joints': {'arm': {'type': 'acme_mit', 'bus': 'can0', 'id': 3}},
        },
        clock_ns=clock,
        bus_factory=sim_factory,
        receive_in_loop=False, families=motors,
    )
    try:
        with hw:
            hw.open()
            world.step(1)
            for _ in range(1000):
                now = clock.advance_ms(1)
                hw.set_command('arm', MODE_MIT, position=0.5, kp=5.0, kd=0.3)
                hw.tick(now)
                world.step(1)
                wait_fresh(hw, now)
            (arm,) = hw.states()
    finally:
        world.close()
    assert arm.online and arm.position == pytest.approx(0.5, abs=0.05)


def test_without_the_entry_point_the_type_is_unknown_to_hardware_and_simulator():
    with pytest.raises(HardwareConfigError, match=r"joints\.arm\.type 'acme_mit' is unknown"):
        CanHardware(
            {
                'buses': {'can0': {'interface': 'virtual', 'channel': 'x'}},
                'joints': {'arm': {'type': 'acme_mit', 'bus': 'can0', 'id': 3}},
            }, families=motors
        )
    with pytest.raises(SimConfigError, match="unknown motor type 'acme_sim'"):
        SimWorld(timing='stepped').add_channel('acme-none', [{'type': 'acme_sim', 'id': 3}])


@pytest.mark.parametrize(
    ('entry_points', 'match'),
    [
        ('acme = acme_motors:NOT_A_FAMILY\n', "'acme' .* is a int, not a MotorFamily"),
        ('acme = acme_motors:MISSING\n', "'acme' .* does not load: AttributeError"),
        ('a = acme_motors:FAMILY\nb = acme_motors:FAMILY\n', "two motor families are named 'acme'"),
    ],
)
def test_a_broken_entry_point_is_a_clear_error(tmp_path, monkeypatch, entry_points, match):
    install(tmp_path, monkeypatch, entry_points)
    with pytest.raises(MotorFamilyError, match=match):
        motors.families()


def test_two_families_cannot_claim_one_joint_type():
    dji = motors.families()['dji']
    twin = MotorFamily(name='twin', actuators=(M3508,))
    with pytest.raises(MotorFamilyError, match="'dji' and 'twin' both define joint type 'm3508'"):
        motors.registry._checked([dji, twin])
