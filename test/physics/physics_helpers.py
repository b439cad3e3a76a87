# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Small teams for the physics engine's tests: configurations and measurements."""

import math

from formation_ros.core.settings.params import validate
import numpy as np

TURTLEBOT = {'body.kind': 'unicycle', 'body.hand_distance': 0.08, 'body.radius': 0.11,
             'body.max_linear': 0.22, 'body.max_angular': 2.84, 'controller.gain': 0.05}


def team(positions, dim=2, headings=None, extra=None):
    """
    Return a validated configuration (formation_sim's) of robots starting at ``positions``.

    extra: more parameters, {dotted name: value}.
    """
    flat = [float(v) for v in np.asarray(positions, dtype=float).ravel()]
    n = len(flat) // dim
    params = {'num_robots': n, 'dim': dim, 'sensing_radius': 2.0, 'repulsion_radius': 0.5,
              'formation.vertices': [float(v) for v in np.arange(n * dim)],
              'start.positions': flat, 'controller.gain': 0.05}
    if headings is not None:
        params['start.headings'] = [float(h) for h in headings]
    params.update(extra or {})
    return validate(params)


def bases(positions, headings=None, extra=None):
    """Return TurtleBot3-like unicycles starting at ``positions`` (N, 2)."""
    return team(positions, 2, headings, {**TURTLEBOT, **(extra or {})})


def tilt(orientations):
    """Return how far each body leans (N,), rad: the angle between its z axis and the world's."""
    x, y = orientations[:, 0], orientations[:, 1]
    cos_tilt = 1.0 - 2.0 * (x * x + y * y)
    return np.arccos(np.clip(cos_tilt, -1.0, 1.0))


def forward_speed(engine):
    """Return each base's speed along its heading (N,), m/s."""
    velocity = engine.velocities()
    heading = engine.poses().headings
    return velocity[:, 0] * np.cos(heading) + velocity[:, 1] * np.sin(heading)


def run(engine, seconds, every=1):
    """Step ``engine`` for ``seconds``; return the poses after every ``every`` steps."""
    steps = int(round(seconds / engine.world.timestep))
    poses = []
    for _ in range(steps // every):
        engine.step(every)
        poses.append(engine.poses())
    return poses


def yaw_difference(a, b):
    """Return a - b wrapped into (-pi, pi]."""
    return (a - b + math.pi) % (2.0 * math.pi) - math.pi
