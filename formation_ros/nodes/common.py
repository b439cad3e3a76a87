"""What every formation node shares: parameter declaration from the schema, start-up, shutdown."""

import difflib
import os
import signal
import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from formation_ros.core.params import ParamError, REQUIRED, SCHEMA, SCHEMA_BY_NAME, validate
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rcl_interfaces.msg import ParameterType
import rclpy
from rclpy.exceptions import (InvalidParameterTypeException, InvalidParameterValueException,
                              ParameterUninitializedException)
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions

_TYPES = {
    'int': (ParameterType.PARAMETER_INTEGER, Parameter.Type.INTEGER),
    'double': (ParameterType.PARAMETER_DOUBLE, Parameter.Type.DOUBLE),
    'string': (ParameterType.PARAMETER_STRING, Parameter.Type.STRING),
    'bool': (ParameterType.PARAMETER_BOOL, Parameter.Type.BOOL),
    'double_array': (ParameterType.PARAMETER_DOUBLE_ARRAY, Parameter.Type.DOUBLE_ARRAY),
}
ROS_OWN_PARAMETERS = ('use_sim_time', 'start_type_description_service', 'qos_overrides.')
FLOAT_MAX = sys.float_info.max
INT_MAX = 2 ** 63 - 1
SIGNAL_LATENCY = 0.1


def descriptor_for(param):
    """Build the ParameterDescriptor of a schema entry: type, description, range, read-only."""
    ros_type, _ = _TYPES[param.kind]
    text = param.description
    if param.choices:
        text += f" One of: {', '.join(param.choices)}."
    descriptor = ParameterDescriptor(name=param.name, type=ros_type, description=text,
                                     read_only=True, dynamic_typing=False)
    if param.kind == 'double' and (param.low is not None or param.high is not None):
        descriptor.floating_point_range = [FloatingPointRange(
            from_value=float(-FLOAT_MAX if param.low is None else param.low),
            to_value=float(FLOAT_MAX if param.high is None else param.high), step=0.0)]
    if param.kind == 'int' and (param.low is not None or param.high is not None):
        descriptor.integer_range = [IntegerRange(
            from_value=int(-INT_MAX if param.low is None else param.low),
            to_value=int(INT_MAX if param.high is None else param.high), step=0)]
    return descriptor


def declare_and_validate(node, executable):
    """
    Declare the parameters ``executable`` reads and validate them with the core's checks.

    Returns a ``FormationConfig``. Raises ParamError naming every bad parameter (wrong type,
    out of range, inconsistent); a parameter in the file that no formation node knows is
    reported as a warning with the closest known name (it may be meant for another tool).
    """
    problems, raw = [], {}
    for param in SCHEMA:
        if executable not in param.users:
            continue
        descriptor = descriptor_for(param)
        try:
            if param.default is REQUIRED or param.default is None:
                node.declare_parameter(param.name, _TYPES[param.kind][1], descriptor)
            else:
                node.declare_parameter(param.name, param.default, descriptor)
            raw[param.name] = node.get_parameter(param.name).value
        except ParameterUninitializedException:
            raw[param.name] = None
        except (InvalidParameterTypeException, InvalidParameterValueException) as exc:
            problems.append((param.name, str(exc).split(': ' + param.name)[0]))
    _warn_unknown(node)
    if problems:
        raise ParamError(problems)
    raw = {name: (list(value) if isinstance(value, (list, tuple)) or hasattr(value, 'tolist')
                  else value) for name, value in raw.items() if value is not None}
    return validate(raw, executable)


def _warn_unknown(node):
    overrides = getattr(node, '_parameter_overrides', {}) or {}
    for name in overrides:
        if name in SCHEMA_BY_NAME or name.startswith(ROS_OWN_PARAMETERS):
            continue
        close = difflib.get_close_matches(name, list(SCHEMA_BY_NAME), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ''
        node.get_logger().warning(f"ignoring unknown parameter '{name}'{hint}")


class OnceLog:
    """Logs a condition once when it starts and once when it ends, not every cycle."""

    def __init__(self, logger):
        """Log through ``logger``."""
        self._logger = logger
        self._active = set()

    def start(self, key, message, level='warning'):
        """Log ``message`` if ``key`` was not already active; return True if logged."""
        if key in self._active:
            return False
        self._active.add(key)
        # rclpy ties a severity to each call site, hence one call per level.
        if level == 'error':
            self._logger.error(message)
        elif level == 'info':
            self._logger.info(message)
        else:
            self._logger.warning(message)
        return True

    def end(self, key, message=None):
        """Mark ``key`` inactive again, logging ``message`` (info) if it was active."""
        if key in self._active:
            self._active.discard(key)
            if message:
                self._logger.info(message)

    def is_active(self, key):
        """Whether ``key`` is active."""
        return key in self._active


DIAGNOSTICS_PERIOD = 1.0
LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN,
          'error': DiagnosticStatus.ERROR}


def diagnostics(stamp, name, level, message, values):
    """
    Build a DiagnosticArray with one status.

    stamp: builtin_interfaces/Time; name: e.g. 'formation_ros/plant'; level: 'ok', 'warn' or
    'error'; values: {key: value}, formatted with ``str`` (floats with 6 significant digits).
    """
    status = DiagnosticStatus(level=LEVELS[level], name=name, message=message,
                              hardware_id='formation_ros')
    status.values = [KeyValue(key=key, value=f'{value:.6g}' if isinstance(value, float)
                              else str(value)) for key, value in values.items()]
    array = DiagnosticArray(status=[status])
    array.header.stamp = stamp
    return array


def make_executor():
    """Return rclpy's EventsExecutor where it exists (far less overhead per callback)."""
    if os.environ.get('FORMATION_EXECUTOR', 'events') == 'events':
        try:
            from rclpy.experimental import EventsExecutor
            return EventsExecutor()
        except ImportError:
            pass
    return SingleThreadedExecutor()


class _StopRequest:
    """Set by the SIGINT/SIGTERM handler; the spin loop checks it between callbacks."""

    signal_name = None

    @classmethod
    def handler(cls, signum, frame):
        cls.signal_name = signal.Signals(signum).name


def run(node_class, args=None, name=None):
    """
    Start rclpy, build the node, spin until SIGINT/SIGTERM, shut down without a traceback.

    Signals are handled in Python (rclpy's own handlers would invalidate the context before
    the node could log its summary): the handler only records the signal, and the spin loop,
    which wakes at least every 0.1 s even when no timer fires (a sim-time timer whose /clock
    stopped), ends between two callbacks; then the node's
    ``finish()`` (if any) runs while ROS is still up, then the node is destroyed and rclpy shut
    down. Invalid parameters end the process with exit code 2 and one line per bad parameter.
    """
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGINT, _StopRequest.handler)
    signal.signal(signal.SIGTERM, _StopRequest.handler)
    node = executor = None
    code = 0
    try:
        node = node_class()
        executor = make_executor()
        executor.add_node(node)
        while rclpy.ok() and _StopRequest.signal_name is None:
            executor.spin_once(timeout_sec=SIGNAL_LATENCY)
    except ParamError as exc:
        logger = rclpy.logging.get_logger(name or node_class.__name__)
        for line in str(exc).splitlines():
            logger.error(f'invalid {line}')
        code = 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        if node is not None:
            finish = getattr(node, 'finish', None)
            if finish is not None:
                finish()
            node.destroy_node()
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()
    return code
