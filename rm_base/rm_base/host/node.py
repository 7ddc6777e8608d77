"""RobotHost: the rm_robot node, which loads the robot's plugins and runs each at its rate."""

from __future__ import annotations

import re
import sys
from enum import Enum
from typing import Any

from rclpy.duration import Duration
from rclpy.node import Node
from std_srvs.srv import SetBool

from rm_base.host.runner import PluginRunner
from rm_base.plugin import PluginBase, PluginLoader, PluginParams
from rm_base.plugin.errors import ParameterError
from rm_base.plugin.node_io import node_io
from rm_base.ros_logging import FastLogger

NODE_NAME = 'rm_robot'

# A plugin name becomes a parameter prefix and a topic/service name token.
_PLUGIN_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*')

# Plugin threads share the GIL: whenever a runner wakes up, a CPU-bound plugin may keep
# the GIL for up to the interpreter's switch interval (5 ms by default) before it yields.
# Measured here: a 200 Hz plugin beside one burning 30 ms per tick overran 278 of 600 ticks
# at 5 ms, 5 of 600 at 1 ms (its rate held at 200 Hz both times).
_GIL_SWITCH_INTERVAL = 0.001  # [s]

# How long shutdown waits for reliable readers (the bridge) to acknowledge zero output [s].
_ACK_TIMEOUT = 0.5


# Overruns above this share of a plugin's ticks (per state period) are logged as warnings.
_OVERRUN_WARN_SHARE = 0.05


class ExecutorKind(Enum):
    """Executor for the ROS callbacks (subscriptions, services, the state timer)."""

    EVENTS = 'events'  # rclpy.experimental.EventsExecutor: ~6x cheaper per callback
    SINGLE_THREADED = 'single_threaded'  # fallback should the EventsExecutor misbehave


class RobotHost(Node):
    """rm_robot: hosts the mechanism plugins of one robot.

    - Reads the robot config from parameters: ``plugins`` (instance names), and per
      plugin ``<name>.type`` (e.g. ``rm_plugins/StandChassis``), ``<name>.enabled``, plus
      ``<name>.rate`` [Hz], ``<name>.command_timeout`` [s] (declared by PluginBase) and
      the plugin's own keys under ``<name>.``.
    - Loads every plugin by type name from the ament index (``PluginLoader``), so a
      plugin package installed beside rm_base works without changing it.
    - Runs each plugin in its own thread at its own rate (``PluginRunner``); ROS callbacks
      run on the executor that ``main`` spins, and only hand data over through the
      plugins' thread-safe inputs.
    - Services: ``~/<name>/enable`` (std_srvs/SetBool) per plugin and
      ``~/enable_all`` (std_srvs/SetBool, true = enable all, false = disable all).
    - Publishes each plugin's rm_msgs/PluginState on ``~/<name>/state`` (latched) at
      every transition and every ``state_period`` seconds, and warns about overruns then.
    - ``shutdown()`` (also run by ``destroy_node``) stops the runners, then disables
      every plugin, so zero output is published before the node goes away.
    - Lowers the interpreter's GIL switch interval to 1 ms (process-wide) so a CPU-bound
      plugin delays the others' ticks by at most about that much.

    Args:
        loader: plugin loader; default searches AMENT_PREFIX_PATH.
        **kwargs: passed to ``rclpy.node.Node`` (``context``, ``parameter_overrides``, ...).

    Raises:
        ConfigError: the config is invalid or a plugin cannot be loaded or initialised;
            the message names the plugin and the key.
    """

    def get_logger(self) -> FastLogger:
        """The node's logger, cheap enough for its 1 kHz and plugin threads (ros_logging)."""
        return self._fast_logger

    def __init__(self, *, loader: PluginLoader | None = None, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        self._fast_logger = FastLogger(super().get_logger())
        sys.setswitchinterval(min(sys.getswitchinterval(), _GIL_SWITCH_INTERVAL))
        self._runners: dict[str, PluginRunner] = {}
        self._shut_down = False
        self._reported_overruns: dict[str, int] = {}
        try:
            self._configure(loader or PluginLoader(warn=self.get_logger().warning))
        except BaseException:
            self._shut_down = True
            for runner in self._runners.values():
                runner.stop()
            super().destroy_node()
            raise

    # -- public -------------------------------------------------------------------------

    @property
    def plugin_names(self) -> list[str]:
        """Instance names, in config order."""
        return list(self._runners)

    def plugin(self, name: str) -> PluginBase:
        """Return the plugin instance name."""
        return self._runners[name].plugin

    def runner(self, name: str) -> PluginRunner:
        """Return the runner of plugin name (tick and overrun counters)."""
        return self._runners[name]

    def shutdown(self, reason: str = 'shutting down') -> None:
        """Stop every runner, then disable every plugin (zero output). Idempotent."""
        if self._shut_down:
            return
        self._shut_down = True
        for runner in self._runners.values():
            if not runner.stop():
                self.get_logger().error(
                    f"plugin '{runner.name}' did not finish its tick; disabling it anyway"
                )
        for runner in self._runners.values():
            try:
                runner.plugin.disable(reason)
            except Exception as err:  # keep turning the others off
                self.get_logger().error(f"disabling plugin '{runner.name}' failed: {err}")
        if self._runners:
            # Give reliable readers (the bridge) the chance to receive the zero output
            # before the publisher disappears.
            try:
                node_io(self).actuator_cmd.wait_for_all_acked(Duration(seconds=_ACK_TIMEOUT))
            except Exception as err:  # e.g. the context is already shut down
                self.get_logger().error(f'zero output may not have been delivered: {err}')

    def destroy_node(self) -> None:
        """Shut the plugins down (zero output), then destroy the node."""
        self.shutdown()
        super().destroy_node()

    # -- set-up -------------------------------------------------------------------------

    def _configure(self, loader: PluginLoader) -> None:
        node_params = PluginParams(self, '', prefix='')
        names = node_params.string_array(
            'plugins',
            description='instance names of the plugins to load, in order',
            unique=True,
        )
        if not names:
            raise ParameterError("parameter 'plugins' is empty: no plugin to run", key='plugins')
        for name in names:
            if not _PLUGIN_NAME.fullmatch(name):
                raise ParameterError(
                    f"parameter 'plugins': {name!r} is not a valid plugin name "
                    '(a letter, then letters, digits or _)',
                    key='plugins',
                )
        state_period = node_params.double(
            'state_period',
            1.0,
            description='period of the PluginState heartbeat',
            unit='s',
            gt=0.0,
        )
        self.executor_kind = node_params.choice(
            'executor',
            ExecutorKind,
            ExecutorKind.EVENTS,
            description='executor for subscriptions, services and timers',
        )

        start_enabled = {}
        for name in names:
            host_params = PluginParams(self, name)
            type_name = host_params.string(
                'type', description='plugin type, e.g. rm_plugins/StandChassis'
            )
            start_enabled[name] = host_params.boolean(
                'enabled', True, description='enable the plugin at start-up'
            )
            plugin = loader.create(type_name, plugin=name)
            plugin.init(self, name, PluginParams(self, name, type_name))
            self._runners[name] = PluginRunner(
                plugin, self.get_clock().now, on_error=self._on_runner_error
            )

        for name, runner in self._runners.items():
            self.create_service(
                SetBool,
                f'~/{name}/enable',
                lambda request, response, runner=runner: self._on_enable(runner, request, response),
            )
        self.create_service(SetBool, '~/enable_all', self._on_enable_all)
        self._state_period = state_period
        self.create_timer(state_period, self._on_state_timer)

        for name, runner in self._runners.items():
            plugin = runner.plugin
            if start_enabled[name]:
                runner.enable()
            self.get_logger().info(
                f"plugin '{name}' ({plugin.type_name}) at {plugin.rate:g} Hz, "
                f'{"enabled" if plugin.enabled else "disabled"}'
                + (f', joints: {", ".join(plugin.joints)}' if plugin.joints else '')
            )
            runner.start()

    # -- callbacks (executor thread) ----------------------------------------------------

    def _on_enable(
        self, runner: PluginRunner, request: SetBool.Request, response: SetBool.Response
    ) -> SetBool.Response:
        response.success, response.message = self._set_enabled(runner, request.data)
        return response

    def _on_enable_all(
        self, request: SetBool.Request, response: SetBool.Response
    ) -> SetBool.Response:
        results = [self._set_enabled(runner, request.data) for runner in self._runners.values()]
        response.success = all(ok for ok, _ in results)
        response.message = '; '.join(message for _, message in results)
        return response

    def _set_enabled(self, runner: PluginRunner, enable: bool) -> tuple[bool, str]:
        if self._shut_down:
            return False, f'{runner.name}: shutting down'
        if not enable:
            runner.disable('disabled by service call')
            return True, f'{runner.name}: disabled'
        try:
            changed = runner.enable()
        except Exception as err:
            self.get_logger().error(f"enabling plugin '{runner.name}' failed: {err}")
            return False, f'{runner.name}: enable failed: {type(err).__name__}: {err}'
        return True, f'{runner.name}: {"enabled" if changed else "already enabled"}'

    def _on_state_timer(self) -> None:
        for name, runner in self._runners.items():
            runner.plugin.publish_state()
            overruns = runner.overruns
            new = overruns - self._reported_overruns.get(name, 0)
            if new > 0:
                self._reported_overruns[name] = overruns
                # A late tick now and then is normal on a loaded machine; warn only when a
                # plugin misses a noticeable share of its ticks, so the warning means
                # something (and does not drown the operator's status line).
                share = new / max(1.0, runner.plugin.rate * self._state_period)
                log = (
                    self.get_logger().warning
                    if share > _OVERRUN_WARN_SHARE
                    else (self.get_logger().debug)
                )
                log(
                    f"plugin '{name}' overran its {runner.plugin.rate:g} Hz period {new} "
                    f'time(s) ({100 * share:.1f} % of its ticks) since the last report '
                    f'({runner.skipped} deadlines skipped in all)'
                )

    def _on_runner_error(self, runner: PluginRunner, err: Exception) -> bool:
        # Something outside plugin.run() failed (e.g. the clock after the context went
        # away): turn the plugin off and end its thread.
        self.get_logger().error(
            f"runner of plugin '{runner.name}' failed, stopping it: {type(err).__name__}: {err}"
        )
        try:
            runner.plugin.disable(f'runner failed: {err}')
        except Exception as inner:
            self.get_logger().error(f"disabling plugin '{runner.name}' failed: {inner}")
        return False
