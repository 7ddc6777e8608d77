"""The Linux GPIO backend against fake gpiod (libgpiod v2) and periphery modules.

The fakes follow the real APIs: ``gpiod.request_lines(path, consumer=, config={offset:
LineSettings})`` returning a request with ``get_value``/``set_value``/``release``, values
``gpiod.line.Value.ACTIVE/INACTIVE``; ``periphery.PWM(chip, channel)`` with ``frequency``
[Hz], ``duty_cycle`` (fraction), ``duty_cycle_ns``, ``enable()``, ``disable()``, ``close()``.
"""

import enum
import sys
import types

import pytest
from rm_plugins.gpio import (
    Bias,
    DigitalLine,
    GpioBackendError,
    GpioConfigError,
    LinuxGpioBackend,
    PinKind,
    PinSpec,
    PwmChannel,
)


class Direction(enum.Enum):
    AS_IS = 1
    INPUT = 2
    OUTPUT = 3


class Value(enum.Enum):
    INACTIVE = 0
    ACTIVE = 1


class FakeBias(enum.Enum):
    AS_IS = 1
    UNKNOWN = 2
    DISABLED = 3
    PULL_UP = 4
    PULL_DOWN = 5


class LineSettings:
    def __init__(self, **kwargs):
        self.__dict__.update(kwargs)


class FakeRequest:
    """Logical values per offset; the physical level is inverted for active-low lines."""

    def __init__(self, chip, consumer, config):
        self.chip, self.consumer, self.config = chip, consumer, config
        self.levels = {}  # offset -> physical level 0/1
        self.released = False
        for offset, settings in config.items():
            if settings.direction is Direction.OUTPUT:
                self.set_value(offset, settings.output_value)

    def _active_low(self, offset):
        return self.config[offset].active_low

    def get_value(self, offset):
        level = self.levels.get(offset, 0)
        return Value.ACTIVE if level != self._active_low(offset) else Value.INACTIVE

    def set_value(self, offset, value):
        assert self.config[offset].direction is Direction.OUTPUT
        self.levels[offset] = int((value is Value.ACTIVE) != self._active_low(offset))

    def release(self):
        self.released = True


def make_fake_gpiod(fail_chip=None):
    gpiod = types.ModuleType('gpiod')
    gpiod.__version__ = '2.5.0'
    gpiod.line = types.SimpleNamespace(Direction=Direction, Value=Value, Bias=FakeBias)
    gpiod.LineSettings = LineSettings
    gpiod.requests = []

    def request_lines(path, *, consumer, config):
        if path == fail_chip:
            raise FileNotFoundError(2, 'No such file or directory', path)
        request = FakeRequest(path, consumer, dict(config))
        gpiod.requests.append(request)
        return request

    gpiod.request_lines = request_lines
    return gpiod


class FakePwm:
    def __init__(self, chip, channel):
        self.chip, self.channel = chip, channel
        # Left over from an earlier user: 10 Hz at 30 % (30 ms high).
        self.period_ns = 100_000_000
        self.duty_cycle_ns = 30_000_000
        self.enabled = False
        self.closed = False
        self.log = []

    @property
    def frequency(self):
        return 1e9 / self.period_ns

    @frequency.setter
    def frequency(self, hz):
        period_ns = round(1e9 / hz)
        if self.duty_cycle_ns > period_ns:  # what the kernel refuses
            raise OSError(22, 'Invalid argument')
        self.period_ns = period_ns

    @property
    def duty_cycle(self):
        return self.duty_cycle_ns / self.period_ns

    @duty_cycle.setter
    def duty_cycle(self, fraction):
        self.duty_cycle_ns = round(fraction * self.period_ns)
        self.log.append(fraction)

    def enable(self):
        self.enabled = True

    def disable(self):
        self.enabled = False

    def close(self):
        self.closed = True


def make_fake_periphery():
    periphery = types.ModuleType('periphery')
    periphery.pwms = []

    def pwm(chip, channel):
        made = FakePwm(chip, channel)
        periphery.pwms.append(made)
        return made

    periphery.PWM = pwm
    return periphery


PINS = {
    'switch': PinSpec(
        'switch',
        PinKind.INPUT,
        line=DigitalLine('/dev/gpiochip0', 5, active_low=True, bias=Bias.PULL_UP),
    ),
    'laser': PinSpec('laser', PinKind.OUTPUT, initial=1.0, line=DigitalLine('/dev/gpiochip0', 6)),
    'buzzer': PinSpec('buzzer', PinKind.OUTPUT, line=DigitalLine('/dev/gpiochip1', 2)),
}
SERVO = PinSpec('servo', PinKind.PWM, initial=0.075, pwm=PwmChannel(0, 1, 50.0))


@pytest.fixture
def gpiod(monkeypatch):
    fake = make_fake_gpiod()
    monkeypatch.setitem(sys.modules, 'gpiod', fake)
    return fake


@pytest.fixture
def periphery(monkeypatch):
    fake = make_fake_periphery()
    monkeypatch.setitem(sys.modules, 'periphery', fake)
    return fake


def test_when_gpiod_is_missing_expect_a_clear_error_naming_the_package(monkeypatch):
    monkeypatch.setitem(sys.modules, 'gpiod', None)  # makes `import gpiod` fail
    with pytest.raises(GpioBackendError, match=r"Python package 'gpiod' \(libgpiod v2"):
        LinuxGpioBackend(PINS)


def test_when_gpiod_is_the_old_v1_api_expect_a_clear_error(monkeypatch):
    old = types.ModuleType('gpiod')
    old.__version__ = '1.5.4'
    old.Chip = object
    monkeypatch.setitem(sys.modules, 'gpiod', old)
    with pytest.raises(GpioBackendError, match=r'gpiod >= 2\.0.*found gpiod 1\.5\.4'):
        LinuxGpioBackend(PINS)


def test_when_periphery_is_missing_expect_a_clear_error_naming_the_package(gpiod, monkeypatch):
    monkeypatch.setitem(sys.modules, 'periphery', None)
    with pytest.raises(GpioBackendError, match="Python package 'python-periphery'"):
        LinuxGpioBackend({**PINS, 'servo': SERVO})
    # The lines requested before the failure are released again.
    assert gpiod.requests and all(r.released for r in gpiod.requests)


def test_when_only_digital_pins_expect_periphery_never_imported(gpiod, monkeypatch):
    monkeypatch.setitem(sys.modules, 'periphery', None)
    with LinuxGpioBackend(PINS) as backend:
        assert backend.read('laser') == 1.0


def test_when_opened_expect_one_request_per_chip_with_the_line_settings(gpiod):
    with LinuxGpioBackend(PINS, consumer='rm_robot/gpio'):
        by_chip = {r.chip: r for r in gpiod.requests}
        assert sorted(by_chip) == ['/dev/gpiochip0', '/dev/gpiochip1']
        chip0 = by_chip['/dev/gpiochip0']
        assert chip0.consumer == 'rm_robot/gpio'
        assert chip0.config[5].direction is Direction.INPUT
        assert chip0.config[5].active_low is True
        assert chip0.config[5].bias is FakeBias.PULL_UP
        assert chip0.config[6].direction is Direction.OUTPUT
        assert chip0.config[6].output_value is Value.ACTIVE  # initial 1
        assert chip0.levels[6] == 1
    assert all(r.released for r in gpiod.requests)


def test_when_an_active_low_switch_pulls_the_line_low_expect_it_read_as_1(gpiod):
    with LinuxGpioBackend(PINS) as backend:
        chip0 = gpiod.requests[0]
        chip0.levels[5] = 1  # pulled up: switch open
        assert backend.read('switch') == 0.0
        chip0.levels[5] = 0  # switch closed to ground
        assert backend.read('switch') == 1.0


def test_when_an_output_is_written_expect_the_line_driven(gpiod):
    with LinuxGpioBackend(PINS) as backend:
        backend.write('buzzer', 1.0)
        chip1 = next(r for r in gpiod.requests if r.chip == '/dev/gpiochip1')
        assert chip1.levels[2] == 1
        assert backend.read('buzzer') == 1.0
        backend.write('buzzer', 0.0)
        assert chip1.levels[2] == 0


def test_when_a_pwm_pin_is_opened_expect_frequency_duty_and_enable(gpiod, periphery):
    with LinuxGpioBackend({'servo': SERVO}) as backend:
        (pwm,) = periphery.pwms
        assert (pwm.chip, pwm.channel) == (0, 1)
        # 50 Hz -> 20 ms period (possible only once the old 30 ms duty time was cleared);
        # 0.075 of 20 ms is 1.5 ms (a servo's centre).
        assert pwm.period_ns == 20_000_000
        assert pwm.duty_cycle_ns == 1_500_000
        assert pwm.enabled
        backend.write('servo', 0.1)
        assert pwm.duty_cycle_ns == 2_000_000
        assert backend.read('servo') == 0.1
    assert pwm.closed and not pwm.enabled


def test_when_a_chip_cannot_be_opened_expect_an_error_naming_chip_and_pins(monkeypatch):
    monkeypatch.setitem(sys.modules, 'gpiod', make_fake_gpiod(fail_chip='/dev/gpiochip1'))
    with pytest.raises(GpioBackendError, match=r'/dev/gpiochip1 for pin\(s\) buzzer'):
        LinuxGpioBackend(PINS)


def test_when_two_pins_share_a_line_expect_a_config_error(gpiod):
    twin = PinSpec('twin', PinKind.OUTPUT, line=DigitalLine('/dev/gpiochip0', 6))
    with pytest.raises(GpioConfigError, match="'laser' and 'twin' are both line 6"):
        LinuxGpioBackend({**PINS, 'twin': twin})


def test_when_a_digital_pin_is_not_wired_expect_a_config_error(gpiod):
    with pytest.raises(GpioConfigError, match="pin 'laser': a digital pin needs a line"):
        LinuxGpioBackend({'laser': PinSpec('laser', PinKind.OUTPUT)})
