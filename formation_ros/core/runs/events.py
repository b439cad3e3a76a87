# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What changed during a run: new shapes and stop / go, as the report and the animation read them.

An :class:`Event` holds from its time on: a SHAPE event's vertices (N, dim), in the formation
frame as ``formation.vertices``, are the shape in force until the next SHAPE event; a STOP event
holds the team until the next START. Before the first event the run's own shape holds (the
trajectory's ``q_desired``) and the team runs. A run is cut into *segments* at its events: the
first opens at the first sample (opened by no event) unless an event is at or before it.
"""

from dataclasses import dataclass
import enum
import math
from typing import Any, Dict, List, Optional, Sequence, Tuple

from formation_ros.core.maths.frames import desired_positions, FrameSample
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.runs.timeline import Mode, Shape, TeamState, Timeline
from formation_ros.core.runs.trajectory import Trajectory
import numpy as np
from numpy.typing import ArrayLike, NDArray


class EventKind(enum.Enum):
    """What an :class:`Event` changes."""

    SHAPE = 'shape'
    STOP = 'stop'
    START = 'start'


@dataclass(frozen=True, eq=False)
class Event:
    """
    A change during a run, in force from time ``t`` (s, the clock of the trajectory's t).

    kind: :class:`EventKind`; label: what to print (a shape's name, 'stop', 'start');
    vertices: (N, dim) desired positions in the formation frame (m) of a SHAPE event, None for
    the others. Compared by identity (the vertices are an array); the vertices are copied and
    read-only. ValueError on a time that is not finite, a SHAPE event without finite (N, dim)
    vertices, or vertices on another kind.
    """

    t: float
    kind: EventKind
    label: str
    vertices: Optional[NDArray[np.float64]] = None

    def __post_init__(self) -> None:
        """Check the event and freeze its vertices."""
        if not isinstance(self.kind, EventKind):
            raise ValueError(f'event kind must be an EventKind, got {self.kind!r}')
        if not math.isfinite(self.t):
            raise ValueError(f'{self.kind.value} event at t = {self.t}: the time must be finite')
        if self.kind is not EventKind.SHAPE:
            if self.vertices is not None:
                raise ValueError(f'{self.kind.value} event at t = {self.t:g} s: only a shape '
                                 'event has vertices')
            return
        if self.vertices is None:
            raise ValueError(f'shape event at t = {self.t:g} s has no vertices')
        vertices = np.array(self.vertices, dtype=float)
        if vertices.ndim != 2 or vertices.shape[0] < 1 or vertices.shape[1] not in (2, 3) \
                or not np.all(np.isfinite(vertices)):
            raise ValueError(f'shape event at t = {self.t:g} s: vertices must be finite '
                             f'(N, 2 or 3) values, got shape {vertices.shape}')
        vertices.setflags(write=False)
        object.__setattr__(self, 'vertices', vertices)


def ordered(events: Sequence[Event]) -> Tuple[Event, ...]:
    """Return the events by time; events at the same time keep their order (the last wins)."""
    return tuple(sorted(events, key=lambda event: event.t))


def _latest(events: Sequence[Event], t: float, kinds: Tuple[EventKind, ...]) -> Optional[Event]:
    found = None
    for event in ordered(events):
        if event.t > t:
            break
        if event.kind in kinds:
            found = event
    return found


def shape_in_force(events: Sequence[Event], t: float) -> Optional[Event]:
    """Return the latest SHAPE event at or before ``t`` (s); None: the run's own shape holds."""
    return _latest(events, t, (EventKind.SHAPE,))


def stopped_at(events: Sequence[Event], t: float) -> bool:
    """Tell whether the team is stopped at ``t`` (s): a STOP at or before t, no START since."""
    latest = _latest(events, t, (EventKind.STOP, EventKind.START))
    return latest is not None and latest.kind is EventKind.STOP


def check_fit(events: Sequence[Event], num_robots: int, dim: int) -> None:
    """Raise ValueError for a shape event whose vertices are not (num_robots, dim)."""
    for event in events:
        if event.vertices is not None and event.vertices.shape != (num_robots, dim):
            raise ValueError(f"shape event '{event.label}' at t = {event.t:g} s has vertices "
                             f'{event.vertices.shape}, the run has {num_robots} robots in '
                             f'{dim}D')


def with_shapes(trajectory: Trajectory, events: Sequence[Event],
                frames: Sequence[FrameSample]) -> Trajectory:
    """
    Return the trajectory with ``q_desired`` (T, N, dim) taken from the shape in force.

    At each sample k with a SHAPE event at or before t[k], q_desired[k] is eq. (20) of that
    event's vertices in ``frames[k]`` (the reference at t[k]); elsewhere it is kept. The input
    is not changed; with no SHAPE event it is returned as is. ValueError when a shape's vertices
    are not (N, dim) of the trajectory or the frames are not one per sample.
    """
    shapes = [event for event in ordered(events) if event.kind is EventKind.SHAPE]
    if not shapes:
        return trajectory
    check_fit(shapes, trajectory.num_robots, trajectory.dim)
    if len(frames) != len(trajectory.t):
        raise ValueError(f'{len(frames)} reference frames for {len(trajectory.t)} samples')
    desired = np.array(trajectory.q_desired, dtype=float)
    times = np.asarray(trajectory.t, dtype=float)
    starts = np.searchsorted(times, [event.t for event in shapes], side='left')
    ends = list(starts[1:]) + [len(times)]
    for event, start, end in zip(shapes, starts, ends):
        vertices = event.vertices
        assert vertices is not None
        for k in range(int(start), int(end)):
            desired[k] = desired_positions(vertices, frames[k])
    return Trajectory(t=trajectory.t, q=trajectory.q, u=trajectory.u, u_hat=trajectory.u_hat,
                      q_desired=desired, q_od=trajectory.q_od, heading=trajectory.heading,
                      q_body=trajectory.q_body, body_command=trajectory.body_command)


@dataclass(frozen=True)
class Segment:
    """
    Part of a run between two events: [start, end) in s (the last one includes its end).

    opened_by: the event that opened it, None for the part before the first event; samples:
    the indices [first, stop) of the trajectory's samples inside it (possibly none).
    """

    start: float
    end: float
    opened_by: Optional[Event]
    first: int
    stop: int


def segments(times: ArrayLike, events: Sequence[Event]) -> List[Segment]:
    """
    Cut the run sampled at ``times`` (T,) in s at its events; [] when there is no event.

    Events after the last sample open nothing and are left out; the part before the first
    event is a segment opened by None when it holds a sample.
    """
    t = np.asarray(times, dtype=float)
    inside = [event for event in ordered(events) if event.t <= t[-1]]
    if not inside:
        return []
    openers: List[Tuple[float, Optional[Event]]] = [(event.t, event) for event in inside]
    if inside[0].t > t[0]:
        openers.insert(0, (float(t[0]), None))
    cut = [int(np.searchsorted(t, start, side='left')) for start, _ in openers] + [len(t)]
    ends = [start for start, _ in openers[1:]] + [float(t[-1])]
    return [Segment(float(start), float(end), event, cut[k], max(cut[k], cut[k + 1]))
            for k, ((start, event), end) in enumerate(zip(openers, ends))]


def timeline_events(shapes: Timeline[Shape], states: Timeline[TeamState]) -> Tuple[Event, ...]:
    """
    Return the events of a run's timelines: each shape switch, each stop and start.

    A change that changes nothing (the reference's first shape when it is the file's, a status
    that keeps the mode) is not an event. Times are the changes' stamps in s.
    """
    events = []
    previous = shapes.initial
    for stamp, shape in shapes.changes():
        if not shape.same_as(previous):
            events.append(Event(stamp / NS_PER_S, EventKind.SHAPE, shape.name or 'new shape',
                                shape.vertices))
        previous = shape
    mode = states.initial.mode
    for stamp, state in states.changes():
        if state.mode is not mode:
            kind = EventKind.STOP if state.mode is Mode.STOPPED else EventKind.START
            events.append(Event(stamp / NS_PER_S, kind, kind.value))
        mode = state.mode
    return ordered(events)


def event_records(events: Sequence[Event]) -> List[Dict[str, Any]]:
    """Return the events as JSON-ready dicts (t, kind, label, vertices), e.g. for plant_stats."""
    return [{'t': event.t, 'kind': event.kind.value, 'label': event.label,
             'vertices': None if event.vertices is None else event.vertices.tolist()}
            for event in events]


def events_from_records(records: Any) -> Tuple[Event, ...]:
    """Inverse of :func:`event_records`; ValueError when the records are not events."""
    if not isinstance(records, list):
        raise ValueError('events must be a list')
    try:
        return ordered([Event(float(record['t']), EventKind(record['kind']),
                              str(record['label']), record.get('vertices'))
                        for record in records])
    except (KeyError, TypeError) as exc:
        raise ValueError(f'not an event record ({exc})') from None
