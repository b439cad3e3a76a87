# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What holds when: the shape in force and the team's mode, as changes stamped with their start.

A formation can change while it runs (a new shape, a stop, a start). Each change holds from its
stamp on, so every node answers a state with the change in force at the state's stamp, whatever
order the messages arrived in: the robots, the plant, the recorder's report and
``formation_sim`` then agree on when a switch happened, to the step.
"""

import bisect
from dataclasses import dataclass
import enum
from typing import Dict, Generic, List, Mapping, Sequence, Tuple, TypeVar

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.reference import Reference
from formation_ros.core.maths.units import NS_PER_S
import numpy as np
from numpy.typing import NDArray

Value = TypeVar('Value')
MAX_CHANGES = 256
"""Changes kept; the oldest are dropped (a state never answers one that old)."""


class Mode(enum.Enum):
    """Whether the team moves (``RUNNING``) or every robot holds still (``STOPPED``)."""

    RUNNING = 'running'
    STOPPED = 'stopped'


@dataclass(frozen=True)
class Shape:
    """A formation shape: its name ('' for ``formation.vertices``) and vertices (N, dim), m."""

    name: str
    vertices: NDArray[np.float64]

    def same_as(self, other: 'Shape') -> bool:
        """Tell whether two shapes have the same vertices (names aside)."""
        return (self.vertices.shape == other.vertices.shape
                and bool(np.array_equal(self.vertices, other.vertices)))


@dataclass(frozen=True)
class TeamState:
    """
    What ``/formation/status`` says from its stamp on: the mode and the reference in force.

    mode: running or stopped; shape: the name of the shape in force ('' for
    ``formation.vertices``); origin (dim,) m, speed m/s, phase rad: the reference's values
    that may change while it runs (``Reference.with_values``).
    """

    mode: Mode
    shape: str
    origin: Tuple[float, ...]
    speed: float
    phase: float

    @classmethod
    def of(cls, mode: Mode, shape: str, reference: Reference) -> 'TeamState':
        """Return the state of a team in ``mode`` with ``shape`` tracking ``reference``."""
        return cls(mode, shape, tuple(float(v) for v in reference.origin), reference.speed,
                   reference.phase)

    def reference(self, base: Reference) -> Reference:
        """Return ``base`` with this state's origin, speed and phase."""
        return base.with_values(self.origin, self.speed, self.phase)


class Timeline(Generic[Value]):
    """
    Values that hold from their stamps (ns) on; the first holds from the beginning of time.

    :meth:`at` returns the value of the latest change stamped at or before a time. A change
    with the stamp of one already kept replaces it. At most :data:`MAX_CHANGES` are kept: the
    oldest change then becomes the value from the beginning (so ``at`` of a time before it
    returns the value that held last, not the first one).
    """

    def __init__(self, initial: Value) -> None:
        """Start with ``initial`` in force from the beginning."""
        self._stamps: List[int] = [-(2 ** 63)]
        self._values: List[Value] = [initial]

    def add(self, stamp_ns: int, value: Value) -> None:
        """Let ``value`` hold from ``stamp_ns`` on (until a later change)."""
        index = bisect.bisect_left(self._stamps, stamp_ns)
        if index < len(self._stamps) and self._stamps[index] == stamp_ns:
            self._values[index] = value
        else:
            self._stamps.insert(index, stamp_ns)
            self._values.insert(index, value)
        while len(self._stamps) > MAX_CHANGES:
            self._values[0] = self._values[1]
            del self._stamps[1], self._values[1]

    def at(self, stamp_ns: int) -> Value:
        """Return the value in force at ``stamp_ns``."""
        return self._values[bisect.bisect_right(self._stamps, stamp_ns) - 1]

    @property
    def initial(self) -> Value:
        """Return the value in force before every change kept."""
        return self._values[0]

    @property
    def latest(self) -> Value:
        """Return the value of the latest change."""
        return self._values[-1]

    def changes(self) -> List[Tuple[int, Value]]:
        """Return (stamp in ns, value) of every change after the initial value, in order."""
        return list(zip(self._stamps[1:], self._values[1:]))


class ReferenceTimeline:
    """
    The reference in force at each time, sampled like a ``Reference``.

    That is ``base`` with the origin, speed and phase of the team state in force (``states``:
    :class:`TeamState` changes stamped in ns).
    """

    def __init__(self, base: Reference, states: 'Timeline[TeamState]') -> None:
        """Follow ``states`` (shared: changes added to it later count)."""
        self.base = base
        self.states = states
        self.kind = base.kind
        self._built: Dict[TeamState, Reference] = {}

    @property
    def is_stationary(self) -> bool:
        """Tell whether q_od never moves (the base's kind; a fixed origin may jump)."""
        return self.base.is_stationary

    def at(self, stamp_ns: int) -> Reference:
        """Return the reference in force at ``stamp_ns``."""
        state = self.states.at(stamp_ns)
        reference = self._built.get(state)
        if reference is None:
            reference = self._built[state] = state.reference(self.base)
        return reference

    def sample(self, t: float) -> FrameSample:
        """Return the frame at t in s, from the reference in force then."""
        return self.at(int(round(t * NS_PER_S))).sample(t)

    def frame_at(self, stamp_ns: int, epoch_ns: int = 0) -> FrameSample:
        """
        Return the frame of the reference in force at ``stamp_ns``, at t = stamp - epoch (s).

        What the reference node publishes for a stamp, and what a robot with the team transport
        evaluates itself for a state's stamp (``epoch_ns`` 0 on simulated time).
        """
        return self.at(stamp_ns).sample((stamp_ns - epoch_ns) / NS_PER_S)


def named_shape(vertices: NDArray[np.float64],
                shapes: Mapping[str, NDArray[np.float64]]) -> Shape:
    """Return the shape of these vertices, named after the named shape they are ('' if none)."""
    for name, known in shapes.items():
        if known.shape == vertices.shape and np.array_equal(known, vertices):
            return Shape(name, vertices)
    return Shape('', vertices)


def scheduled_shapes(initial: Shape, schedule: Sequence[Tuple[float, str]],
                     shapes: Mapping[str, NDArray[np.float64]]) -> 'Timeline[Shape]':
    """Return the shapes of a switch schedule ((time in s, name) pairs) after ``initial``."""
    timeline = Timeline(initial)
    for time_s, name in schedule:
        timeline.add(int(round(time_s * NS_PER_S)), Shape(name, shapes[name]))
    return timeline
