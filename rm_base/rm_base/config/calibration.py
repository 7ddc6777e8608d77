"""The calibration file: what the calibration services measured, kept across restarts.

One YAML file that the robot config names (``calibration.file`` of can_bridge, and of the
Hi220 plugin); the services write it, the nodes read it at start-up, where its values
replace the config's. The same file may serve several nodes, each its own section::

    joints:
      yaw: {zero_offset: 1.2345}        # [rad] can_bridge: <joint>/set_zero
    imu:
      imu: {gyro_bias: [0.001, -0.002, 0.0]}   # [rad/s] rm_robot: <plugin>/calibrate_gyro

A write takes an advisory lock (``fcntl.flock`` on ``<file>.lock``), reads the file again,
changes its own entry and replaces the file atomically (``os.replace``), so two nodes
writing at once lose nothing and a reader never sees half a file. No ROS here.
"""

from __future__ import annotations

import contextlib
import fcntl
import math
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import yaml

from rm_base.errors import ConfigError

_HEADER = "# Written by rm_ros2's calibration services; values replace the robot config's.\n"


class CalibrationError(ConfigError):
    """A calibration file that cannot be read or written, or a value in it that is invalid."""


def expand_path(path: str) -> Path:
    """``~`` and ``${VAR}`` expanded (a config names the file portably).

    ``${ROS_HOME}`` is ROS's own folder for a node's files: the variable if set, else
    ``~/.ros``, as rcl takes it for its logs.
    """
    ros_home = os.environ.get('ROS_HOME') or os.path.join(os.path.expanduser('~'), '.ros')
    path = path.replace('${ROS_HOME}', ros_home).replace('$ROS_HOME', ros_home)
    return Path(os.path.expandvars(os.path.expanduser(path)))


class CalibrationFile:
    """One calibration file (see the module docstring).

    Args:
        path: the file; ``~`` and ``${VAR}`` are expanded. It need not exist yet.
    """

    def __init__(self, path: str) -> None:
        self.path = expand_path(path)

    def read(self) -> dict[str, Any]:
        """The whole file as a dict; {} if it does not exist.

        Raises:
            CalibrationError: unreadable, not YAML, or not a mapping at the top.
        """
        try:
            text = self.path.read_text(encoding='utf-8')
        except FileNotFoundError:
            return {}
        except OSError as err:
            raise CalibrationError(f'calibration file {self.path}: {err.strerror}') from err
        except UnicodeDecodeError as err:
            raise CalibrationError(
                f'calibration file {self.path} is not a text file (byte {err.start} is not '
                'UTF-8)') from None
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as err:
            raise CalibrationError(f'calibration file {self.path} is not YAML: {err}') from err
        if data is None:
            return {}
        if not isinstance(data, dict):
            raise CalibrationError(
                f'calibration file {self.path} must be a mapping, not {type(data).__name__}'
            )
        return data

    def entries(self, section: str, keys: Sequence[str]) -> dict[str, dict[str, Any]]:
        """The entries of one section (``joints``, ``imu``) by name; {} if none.

        keys: the keys an entry may have (a typo is an error, not a value ignored).

        Raises:
            CalibrationError: the file is invalid, the section is not a mapping of mappings,
                or an entry has another key (the message names it).
        """
        found = self.read().get(section, {})
        if not isinstance(found, dict) or not all(isinstance(v, dict) for v in found.values()):
            raise CalibrationError(
                f'calibration file {self.path}: {section} must map names to their values'
            )
        for name, values in found.items():
            unknown = sorted(str(k) for k in values if k not in keys)
            if unknown:
                raise CalibrationError(
                    f'calibration file {self.path}: {section}.{name}.{unknown[0]} is not a '
                    f'calibration key (known: {", ".join(keys)})')
        return {str(name): dict(values) for name, values in found.items()}

    def write(self, section: str, name: str, values: dict[str, Any]) -> None:
        """Set ``section.name`` to values (other entries are kept), atomically.

        Raises:
            CalibrationError: the directory cannot be created or the file written, or the
                file holds something that is not a calibration.
        """
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with self._locked():
                data = self.read()
                entries = data.setdefault(section, {})
                if not isinstance(entries, dict):
                    raise CalibrationError(
                        f'calibration file {self.path}: {section} is not a mapping'
                    )
                entries[name] = values
                fd, tmp = tempfile.mkstemp(prefix=self.path.name, dir=self.path.parent)
                try:
                    with os.fdopen(fd, 'w', encoding='utf-8') as out:
                        out.write(_HEADER)
                        yaml.safe_dump(data, out, default_flow_style=None, sort_keys=True)
                    os.replace(tmp, self.path)
                except BaseException:
                    with contextlib.suppress(FileNotFoundError):
                        os.unlink(tmp)
                    raise
        except OSError as err:
            raise CalibrationError(f'calibration file {self.path}: {err}') from err

    @contextlib.contextmanager
    def _locked(self) -> Iterator[None]:
        with open(self.path.with_name(self.path.name + '.lock'), 'a') as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)


def finite_values(
    where: str, value: Any, length: int | None = None, *, limit: float | None = None
) -> tuple[float, ...]:
    """A number (length None) or a list of length numbers from a calibration entry, finite.

    limit: largest magnitude a measured value can have; beyond it the file is wrong.

    Raises:
        CalibrationError: not numbers, the wrong length, not finite or beyond limit; where
            names it.
    """
    items: Sequence[Any] = [value] if length is None else value
    if length is not None and (not isinstance(value, list) or len(value) != length):
        raise CalibrationError(f'{where} must be a list of {length} numbers, got {value!r}')
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in items):
        raise CalibrationError(f'{where} must be numbers, got {value!r}')
    numbers = tuple(float(v) for v in items)
    if not all(math.isfinite(v) for v in numbers):
        raise CalibrationError(f'{where} must be finite, got {value!r}')
    if limit is not None and any(abs(v) > limit for v in numbers):
        raise CalibrationError(
            f'{where} is {value!r}: beyond {limit:g}, no calibration measures that')
    return numbers


def joint_zero_offsets(file: CalibrationFile) -> dict[str, float]:
    """``joints.<name>.zero_offset`` [rad] of every joint the file has.

    Raises:
        CalibrationError: the file or a value is invalid (the message names the key).
    """
    zeros = {}
    for joint, values in file.entries('joints', ('zero_offset',)).items():
        if 'zero_offset' in values:  # set_zero writes an angle in [0, 2 pi)
            (zeros[joint],) = finite_values(
                f'{file.path}: joints.{joint}.zero_offset', values['zero_offset'],
                limit=2.0 * math.pi,
            )
    return zeros
