"""Start rm_sim (the simulated motors, in a process of their own) and point a robot at it.

    with SimProcess(files, workdir) as sim:      # rm_sim serving the robot's channels
        files += [sim.bridge_overlay]            # can_bridge: every bus on rm_sim_socket

``bridge_overlay`` is a parameter file for can_bridge, loaded after the robot config and
its simulation overlay: ``sim: false`` (no in-process simulator) and every bus with
``interface: rm_sim_socket`` on rm_sim's socket. The robot then runs exactly as on
socketcan; only the interface name differs.

With ``interface='socketcan'`` rm_sim answers on the kernel's CAN interfaces named as the
robot's channels (vcan interfaces called can0, can1 ...: docs/KERNEL_CAN.md) and the
overlay leaves the buses as the robot config has them: the robot runs unchanged.
"""

from __future__ import annotations

import copy
import os
import pathlib
import signal
import subprocess
import sys
import time
from collections.abc import Sequence

import yaml
from rm_base.bridge.sim_process import BRIDGE_SECTION, bridge_parameters
from rm_base.errors import ConfigError
from rm_base.sim.socket_bus import INTERFACE_NAME

#: How long rm_sim may take to build its world and listen [s].
START_TIMEOUT_S = 20.0
#: How long it may take to stop on SIGINT before it is killed [s].
STOP_TIMEOUT_S = 10.0


class SimProcess:
    """rm_sim for the robot of files (see the module docstring).

    Args:
        files: the robot's parameter files (config, then its simulation overlay).
        workdir: a private folder for the socket, the overlay and rm_sim's log.

    Raises:
        ConfigError: rm_sim did not come up (its log's last lines are in the message).
    """

    def __init__(self, files: Sequence[pathlib.Path], workdir: pathlib.Path,
                 interface: str | None = None) -> None:
        workdir.mkdir(parents=True, exist_ok=True)
        self.socket = str(workdir / 'can.sock')
        self.log_path = workdir / 'rm_sim.log'
        self.interface = interface
        buses = sorted(
            {k.split('.')[1] for k in bridge_parameters(files) if k.startswith('buses.')}
        )
        parameters: dict[str, object] = {'sim': False}
        if interface is None:
            parameters['buses'] = {
                bus: {'interface': INTERFACE_NAME, 'options': {'socket': self.socket}}
                for bus in buses
            }
        self.bridge_overlay = workdir / 'rm_sim_bridge.yaml'
        self.bridge_overlay.write_text(
            # rcl applies a node's sections in the order their names first appear, so a
            # dump's `/can_bridge:` after the config's `can_bridge:` wins whatever the file
            # order: under both names, this run's socket wins over an earlier run's
            yaml.safe_dump({name: {'ros__parameters': copy.deepcopy(parameters)}  # no alias
                            for name in (BRIDGE_SECTION, f'/{BRIDGE_SECTION}')})
        )
        args = [sys.executable, '-m', 'rm_base.bridge.sim_process', '--socket', self.socket,
                '--parent-pid', str(os.getpid())]
        if interface is not None:
            args += ['--interface', interface]
        for path in files:
            args += ['--params-file', str(path)]
        self._log = open(self.log_path, 'wb')
        self.process = subprocess.Popen(
            args, stdout=self._log, stderr=subprocess.STDOUT, env=dict(os.environ)
        )
        try:
            self._wait_listening()
        except BaseException:
            self.stop()
            raise

    def _listening(self) -> bool:
        if self.interface is None:
            return os.path.exists(self.socket)
        # rm_sim says "[rm_sim] can0, can1 on socketcan" once every channel's bus is open
        return f' on {self.interface}' in self.log_path.read_text(errors='replace')

    def _wait_listening(self) -> None:
        deadline = time.monotonic() + START_TIMEOUT_S
        while not self._listening():
            if self.process.poll() is not None or time.monotonic() > deadline:
                tail = self.log_path.read_text(errors='replace').strip().splitlines()[-5:]
                raise ConfigError('rm_sim did not start: ' + (' | '.join(tail) or 'no output'))
            time.sleep(0.05)

    def stop(self) -> None:
        """SIGINT, then wait (kill after STOP_TIMEOUT_S). Idempotent."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()

    def __enter__(self) -> SimProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
