"""RobotHost: the rm_robot node, which loads the robot's plugins and runs them in one loop."""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Collection
from enum import Enum
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from rcl_interfaces.msg import SetParametersResult
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_srvs.srv import SetBool

from rm_base.config.schema import InvalidValueError
from rm_base.errors import ConfigError
from rm_base.hardware import CanHardware
from rm_base.host.command_sources import read_command_sources
from rm_base.host.plugin_task import PluginTask, TickInputs
from rm_base.host.process_params import process_settings
from rm_base.host.unread_keys import unknown_keys_error, unread_keys
from rm_base.loop import Scheduler
from rm_base.loop.data import PUBLISHED
from rm_base.plugin import PluginBase, PluginLoader, PluginParams
from rm_base.plugin.command_mux import CommandMux
from rm_base.plugin.command_mux_status import command_sources_status
from rm_base.plugin.command_status import CommandReport
from rm_base.plugin.errors import ParameterError
from rm_base.plugin.inbox import STAGE_NAME as INBOX_STAGE
from rm_base.plugin.inbox import Inbox
from rm_base.plugin.inbox_status import InboxReport
from rm_base.plugin.node_io import DdsJointIO, LocalJointIO, NodeIO
from rm_base.plugin.outbox import Outbox
from rm_base.ros.double_parameters import integers_as_doubles
from rm_base.ros.log import FastLogger
from rm_base.ros.node_main import inbox_node
from rm_base.runtime.realtime import shorten_gil_switch_interval

NODE_NAME = 'rm_robot'

# A plugin name becomes a parameter prefix and a topic/service name token.
_PLUGIN_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*')

# How long shutdown waits for reliable readers (the bridge) to acknowledge zero output [s].
_ACK_TIMEOUT = 0.5


class ExecutorKind(Enum):
    """Executor for the ROS callbacks (subscriptions, services, the state timer)."""

    EVENTS = 'events'  # rclpy.experimental.EventsExecutor: ~6x cheaper per callback
    SINGLE_THREADED = 'single_threaded'  # fallback should the EventsExecutor misbehave


class RobotHost(Node):
    """rm_robot: hosts the mechanism plugins of one robot in the control loop.

    - Reads the robot config from parameters: ``plugins`` (instance names), and per
      plugin ``<name>.type`` (e.g. ``rm_plugins/StandChassis``), ``<name>.enabled``, plus
      ``<name>.rate`` [Hz], ``<name>.command_timeout`` [s] (declared by PluginBase) and
      the plugin's own keys under ``<name>.``.
    - Loads every plugin by type name from the ament index (``PluginLoader``), so a
      plugin package installed beside rm_base works without changing it.
    - Runs every plugin as a stage of one loop thread (``PluginTask``), each at its own
      rate and at the next tick after a new command. Given the CAN hardware (the
      one-process robot), that loop is the hardware's own 1 kHz loop and plugins set
      joint targets on the actuators directly; without it (rm_robot as a process of its
      own) the host runs a loop of plugins only, at ``loop_rate``, and joint targets go
      out on /actuator_cmd.
    - ROS stays at the edge: the loop's first stage hands out what the ``Inbox``'s
      thread took from the plugins' subscriptions (no executor, no take from DDS in
      the loop) and their callbacks store the latest command; every message a plugin
      publishes goes through an outbox thread, never from the loop thread. The
      executor ``main`` spins runs only services and the state timer.
    - Services: ``~/<name>/enable`` (std_srvs/SetBool) per plugin and
      ``~/enable_all`` (std_srvs/SetBool, true = enable all, false = disable all).
    - Publishes each plugin's rm_msgs/PluginState on ``~/<name>/state`` (latched) at
      every transition and every ``state_period`` seconds, and with them its inbox's
      status on /diagnostics (``<node>: inbox``: messages taken and dropped per topic).
    - ``shutdown()`` (also run by ``destroy_node``) takes the plugins out of the loop,
      then disables every plugin, so zero output is sent before the node goes away.
    - Lowers the interpreter's GIL switch interval to 0.5 ms (process-wide) so a busy
      ROS thread delays a loop tick by at most about that much.

    Args:
        loader: plugin loader; default searches AMENT_PREFIX_PATH.
        hardware: the CAN hardware to drive in-process (its loop runs the plugins);
            None: DDS joint I/O and a loop of the host's own.
        now: the plugins' clock (default: the node clock's ``now``).
        take_from_dds: the loop takes the plugins' subscriptions from DDS (an
            ``Inbox``); False for lockstep, where commands come only through ``inject``
            (and what the plugins publish, which always reaches them at once).
        node_name: ``rm_robot``, or another host of the same robot (``rm_manual``: a
            commander whose topics the robot's plugins must hear beside other nodes').
        **kwargs: passed to ``rclpy.node.Node`` (``context``, ``parameter_overrides``, ...).

    Raises:
        ConfigError: the config is invalid or a plugin cannot be loaded or initialised;
            the message names the plugin and the key.
    """

    def get_logger(self) -> FastLogger:
        """The node's logger, cheap enough for the 1 kHz loop thread (ros_logging)."""
        return self._fast_logger

    def __init__(
        self,
        *,
        loader: PluginLoader | None = None,
        hardware: CanHardware | None = None,
        now: Callable[[], Any] | None = None,
        take_from_dds: bool = True,
        node_name: str = NODE_NAME,
        **kwargs: Any,
    ) -> None:
        super().__init__(node_name, **kwargs)
        self._fast_logger = FastLogger(super().get_logger())
        shorten_gil_switch_interval()
        self._tasks: dict[str, PluginTask] = {}
        self._shut_down = False
        self._outbox = Outbox(f'{node_name}-publish')
        io: NodeIO
        self.loop: Scheduler | None
        if hardware is not None:
            io = LocalJointIO(self, hardware)
            self.loop = hardware.scheduler
            self._own_loop = False
            inputs = TickInputs(now or self.get_clock().now, io.refresh, self.loop.time_left_ns)
        else:
            io = DdsJointIO(self)
            self.loop = None  # built in _configure, once loop_rate is read
            self._own_loop = True
            inputs = TickInputs(now or self.get_clock().now)
        io.outbox = self._outbox
        # what a plugin publishes reaches the robot's other plugins in-process, not over DDS
        self._outbox.loopback = io.deliver
        self._outbox.listens = io.listens
        self._outbox.loopback_at_put = not take_from_dds  # lockstep: in the same tick
        # Lockstep: every command comes through inject; DDS deliveries would arrive at
        # ticks that differ from run to run, so nothing takes them.
        self._inbox = Inbox(inbox_node(self), self.get_clock()) if take_from_dds else None
        io.inbox = self._inbox
        self._inbox_report = InboxReport(node_name)
        self._command_report = CommandReport(node_name)
        self._diagnostics_pub = self._outbox.wrap(
            self.create_publisher(DiagnosticArray, '/diagnostics', 10))
        self._warned_foreign: set[str] = set()
        self._io = io
        self._outbox.start()
        try:
            self._configure(loader or PluginLoader(warn=self.get_logger().warning), inputs)
        except BaseException:
            self._shut_down = True
            self._leave_loop()
            io.release()
            self._outbox.stop()
            self._destroy_inbox()
            super().destroy_node()
            raise

    # -- public -------------------------------------------------------------------------

    @property
    def plugin_names(self) -> list[str]:
        """Instance names, in config order."""
        return list(self._tasks)

    def plugin(self, name: str) -> PluginBase:
        """Return the plugin instance name."""
        return self._tasks[name].plugin

    def inject(self, topic: str, msg: Any) -> int:
        """Hand msg to the plugins subscribed to topic as if it had arrived now.

        The same callbacks the subscriptions run; for lockstep tests and tools that drive
        the robot without DDS. Returns the number of callbacks that got it.
        """
        return self._io.inject(topic, msg)

    def add_local_handler(self, topic: str, callback: Callable[[Any, int], Any]) -> None:
        """Also give callback(msg, receive_ns) what ``inject`` hands to topic's plugins.

        That includes every message the plugins publish on it.
        """
        self._io.add_handler(self.resolve_topic_name(topic), callback)

    def task(self, name: str) -> PluginTask:
        """Return the loop task of plugin name (run and skip counters)."""
        return self._tasks[name]

    def shutdown(self, reason: str = 'shutting down') -> None:
        """Take the plugins out of the loop, then disable each (zero output). Idempotent."""
        if self._shut_down:
            return
        self._shut_down = True
        self._leave_loop()
        for task in self._tasks.values():
            try:
                task.disable(reason)  # waits for a run in progress, through the lock
            except Exception as err:  # keep turning the others off
                self.get_logger().error(f"disabling plugin '{task.plugin.name}' failed: {err}")
        self._io.release()
        self._outbox.stop()
        if self._tasks and isinstance(self._io, DdsJointIO):
            # Give reliable readers (the bridge) the chance to receive the zero output
            # before the publisher disappears.
            try:
                self._io.actuator_cmd.wait_for_all_acked(Duration(seconds=_ACK_TIMEOUT))
            except Exception as err:  # e.g. the context is already shut down
                self.get_logger().error(f'zero output may not have been delivered: {err}')

    def _leave_loop(self) -> None:
        if self.loop is None:
            return
        if self._own_loop:
            self.loop.stop()
        else:
            self.loop.remove_stage(INBOX_STAGE)
            for task in self._tasks.values():
                self.loop.remove_stage(task.name)
            self.loop.remove_after_tick(self._outbox.wake)

    def _destroy_inbox(self) -> None:
        if self._inbox is not None:
            self._inbox.destroy()
            self._inbox = None

    def destroy_node(self) -> None:
        """Shut the plugins down (zero output), then destroy the node."""
        self.shutdown()
        self._destroy_inbox()
        super().destroy_node()

    # -- set-up -------------------------------------------------------------------------

    def _configure(self, loader: PluginLoader, inputs: TickInputs) -> None:
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
        process = process_settings(node_params)
        sources = read_command_sources(node_params)
        if sources:
            self._io.command_mux = CommandMux(sources, on_switch=self._on_source_switch)
        self.edge_priority = process.edge_priority
        self.cpu_index = process.cpu_index
        self.cpu_latency_us = process.cpu_latency_us
        loop = self.loop
        if loop is None:  # rm_robot as a process of its own
            loop = self.loop = Scheduler(
                [], [], rate_hz=process.loop_rate, thread_name=f'{self.get_name()}-loop',
                priority=process.loop_priority,
            )
            inputs.time_left = loop.time_left_ns

        # the plugins, their devices and the inbox join the loop together, checked at the end
        with loop.compose():
            self._io.loop = loop
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
                plugin.init(self, name, PluginParams(self, name, type_name), self._io)
                # one loop period apart: plugins of like rates do not all fall on one tick
                phase_ns = len(self._tasks) * loop.period_ns
                self._tasks[name] = PluginTask(plugin, inputs, phase_ns, self._io.targets_datum)

            for name, task in self._tasks.items():
                self.create_service(
                    SetBool,
                    f'~/{name}/enable',
                    functools.partial(self._on_enable, task),
                )
            self.create_service(SetBool, '~/enable_all', self._on_enable_all)
            self.create_timer(state_period, self._on_state_timer)

            if self._inbox is not None:  # first: a command reaches its plugin in the same tick
                loop.add_stage(self._inbox)
            self._outbox.pace()  # publishes in the loop's idle time
            loop.add_after_tick(self._outbox.wake, reads=(PUBLISHED,))
            for name, task in self._tasks.items():
                plugin = task.plugin
                if start_enabled[name]:
                    task.enable()
                self.get_logger().info(
                    f"plugin '{name}' ({plugin.type_name}) at {plugin.rate:g} Hz, "
                    f'{"enabled" if plugin.enabled else "disabled"}'
                    + (f', joints: {", ".join(plugin.joints)}' if plugin.joints else '')
                )
                loop.add_stage(task)
        self._check_unread_keys(names)
        # derived from what each component reads and writes (rm_base.loop.order)
        self.get_logger().info(f'loop order: {" -> ".join(loop.order())}')
        # after every declaration: rclpy calls it for the declarations too
        self.add_on_set_parameters_callback(self._on_set_parameters)
        # a live `max_hz 8` keeps the double that `max_hz: 8.0` in a file gave
        self.add_pre_set_parameters_callback(integers_as_doubles(self))
        if self._own_loop:
            loop.start()

    def _check_unread_keys(self, plugins: Collection[str]) -> None:
        """Refuse keys of the files that nothing declared (rm_base.host.unread_keys)."""
        # rclpy keeps the files' values for the node in this attribute and offers no
        # public view of them (rclpy 7.1.6, pinned)
        given = getattr(self, '_parameter_overrides', {})
        declared = set(self.list_parameters([], 0).names)
        found = unread_keys(given, declared, plugins)
        if found.unknown:
            first = found.unknown[0]
            raise ParameterError(
                unknown_keys_error(self.get_name(), found.unknown, declared), key=first
            )
        if found.idle_plugins:
            self.get_logger().info(
                f"the config of {', '.join(found.idle_plugins)} is not read: not in 'plugins'"
            )

    # -- callbacks (executor thread) ----------------------------------------------------

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """``ros2 param set``: the plugins take the call whole or refuse it (see below)."""
        result = self._take_parameters(parameters)
        if not result.successful:
            # rclpy typed the stored descriptor (dynamic typing) after the value it was
            # offered, so `param describe` said "string" for a double after a refused 'fast'
            for parameter in parameters:
                if self.has_parameter(parameter.name):
                    self.describe_parameter(parameter.name).type = (
                        self.get_parameter(parameter.name).type_.value)
        return result

    def _take_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Tunable plugin keys, all of one call together, or none.

        Each plugin checks its keys against its parameter set (bounds, and the set's own
        checks) and takes the new set at the start of its next run, so the values of one
        call (a loop's kp, ki and kd) are never used torn.
        """
        changes: dict[str, dict[str, object]] = {}
        for parameter in parameters:
            if parameter.name == 'use_sim_time':  # rclpy's own, switched live by its clock
                continue
            plugin, _, inner = parameter.name.partition('.')
            if plugin not in self._tasks or not inner:
                return SetParametersResult(
                    successful=False,
                    reason=f'{parameter.name} is read at start-up: a change needs a restart',
                )
            changes.setdefault(plugin, {})[inner] = parameter.value
        proposed = {}
        for plugin, values in changes.items():
            try:
                proposed[plugin] = self._tasks[plugin].plugin.propose_config(values)
            except (InvalidValueError, ConfigError) as err:
                return SetParametersResult(successful=False, reason=f'{plugin}.{err}')
        for plugin, config in proposed.items():
            self._tasks[plugin].plugin.set_config(config)
        self.get_logger().info(
            'set ' + ', '.join(f'{p.name} = {p.value!r}' for p in parameters)
            + ' (from the next run on)'
        )
        return SetParametersResult(successful=True)

    def _on_enable(
        self, task: PluginTask, request: SetBool.Request, response: SetBool.Response
    ) -> SetBool.Response:
        response.success, response.message = self._set_enabled(task, request.data)
        return response

    def _on_enable_all(
        self, request: SetBool.Request, response: SetBool.Response
    ) -> SetBool.Response:
        results = [self._set_enabled(task, request.data) for task in self._tasks.values()]
        response.success = all(ok for ok, _ in results)
        response.message = '; '.join(message for _, message in results)
        return response

    def _set_enabled(self, task: PluginTask, enable: bool) -> tuple[bool, str]:
        name = task.plugin.name
        if self._shut_down:
            return False, f'{name}: shutting down'
        if not enable:
            task.disable('disabled by service call')
            return True, f'{name}: disabled'
        try:
            changed = task.enable()
        except Exception as err:
            self.get_logger().error(f"enabling plugin '{name}' failed: {err}")
            return False, f'{name}: enable failed: {type(err).__name__}: {err}'
        return True, f'{name}: {"enabled" if changed else "already enabled"}'

    def _on_source_switch(self, topic: str, old: str, new: str, why: str) -> None:
        # the loop's thread, on a message or a report: rare, and said at once
        self.get_logger().info(
            f"command source of {topic}: {old or 'none'} -> {new or 'none'}"
            + (f' ({why})' if why else ''))

    def _on_state_timer(self) -> None:
        for task in self._tasks.values():
            task.plugin.publish_state()
        inbox, mux = self._inbox, self._io.command_mux
        inputs = [(name, command) for name, task in self._tasks.items()
                  for command in task.plugin.command_inputs]
        if (inbox is not None or mux is not None or inputs) and self._diagnostics_pub.heard():
            now = self.get_clock().now()
            msg = DiagnosticArray()
            msg.header.stamp = now.to_msg()
            if inbox is not None:
                msg.status.append(self._inbox_report.status(inbox))
            if inputs:
                msg.status.append(self._command_report.status(inputs))
            if mux is not None and mux.topics:  # rm_manual takes no command: nothing to say
                msg.status.append(
                    command_sources_status(self.get_name(), mux, now.nanoseconds))
            self._diagnostics_pub.publish(msg)
        for topic, count in self._io.foreign_publishers().items():
            if topic not in self._warned_foreign:
                self._warned_foreign.add(topic)
                self.get_logger().warning(
                    f'{count} publisher(s) of other nodes on {topic}: not heard by the '
                    "plugins, which take that topic from this robot's own plugin"
                )
