# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What every node of one team must agree on, as short texts that nodes announce and compare.

Two nodes started with different parameters files (a robot on another computer with an old
copy) run, but the team never forms. Each node announces these values in its ``/diagnostics``
status; the plant and the reference compare them with their own and name the node that differs
(``ros.team``).

Two teams on one domain hear each other: a topic with a second publisher is found in the ROS
graph and reported as :func:`duplicate_due` says.
"""

import hashlib
from typing import Any, Dict, Mapping, Optional, Sequence

from formation_ros.core.settings.params import FormationConfig
import numpy as np
from numpy.typing import NDArray

DIGITS = 12
FRAME_VALUES = ('num_robots', 'dim', 'world_frame', 'repulsion_radius')
"""Parameters of the team's frame and size: announced (:func:`team_values`) and deciding, with
every :data:`REFERENCE_PREFIXES` one, how a robot checks the reference
(:func:`reference_values`)."""
LAW_VALUES = ('controller.gain', 'controller.kappa', 'controller.psi', 'jump.kind',
              'jump.order', 'body.kind', 'body.hand_distance')
"""Parameters of the law and the bodies, announced by :func:`team_values`."""
LINK_VALUES = FRAME_VALUES + LAW_VALUES + ('command.type', 'command.frame', 'plant.lockstep',
                                           'transport', 'body.radius', 'obstacles.clearance',
                                           'obstacles.source')
"""Parameters the robots of one process with ``transport: team`` share: one call of the law
computes their commands, with one footprint and clearance b_o against obstacles, told or seen
(the watchdog and input timeout are the first robot's)."""
REFERENCE_PREFIXES = ('reference.', 'formation.', 'formations.')
"""Prefixes of the parameters that decide the reference a robot follows and its changes."""
DUPLICATE_GRACE = 25.0
"""A second publisher with the expected node's own name is reported after this many seconds
without other evidence that it runs: a node restarted after a hard kill shares its topics with
the dead process's publishers until DDS lets go of them (about 20 s with Fast DDS's default
participant lease)."""


def digest(values: NDArray[np.float64]) -> str:
    """Return a short fingerprint of an array's exact values (shape and float64 bytes)."""
    array = np.ascontiguousarray(values, dtype=np.float64)
    data = repr(array.shape).encode() + array.tobytes()
    return hashlib.sha256(data).hexdigest()[:DIGITS]


def team_values(config: FormationConfig, shape: NDArray[np.float64]) -> Dict[str, str]:
    """
    Return what must agree across the team: {name: text}.

    num_robots, dim, the law's constants (c, kappa, psi, the jump function, b), the sensing radii
    and the shape in force (``shape``, (N, dim): fingerprints of their exact values), the world
    frame, the bodies and (for the programs that read it) the transport.
    """
    body = config.body
    values = {
        'num_robots': str(config.num_robots), 'dim': str(config.dim),
        'law': (f'c={config.gain!r} kappa={config.kappa!r} psi={config.psi.value} '
                f'jump={config.jump_kind.value}/{config.jump_order} '
                f'b={config.repulsion_radius!r}'),
        'sensing radii': digest(config.sensing_radii),
        'shape in force': digest(shape),
        'world_frame': config.world_frame,
        'body': (f'{body.kind.value} l={body.hand_distance!r}' if body.is_unicycle
                 else body.kind.value),
    }
    if 'transport' in config.values:
        values['transport'] = config.transport.value
    return values


def reference_values(values: Mapping[str, Any]) -> Dict[str, Any]:
    """
    Return the parameter values (``FormationConfig.values``) that decide a robot's reference.

    :data:`FRAME_VALUES` and every ``reference.*``, ``formation.*`` and ``formations.*``: a
    fleet's robot that has the first robot's values hears the reference and the changes
    through it.
    """
    return {name: value for name, value in values.items()
            if name in FRAME_VALUES or name.startswith(REFERENCE_PREFIXES)}


def differences(own: Mapping[str, str], other: Mapping[str, str]) -> Dict[str, str]:
    """Return {name: 'theirs (ours)'} for every value ``other`` announces differently."""
    return {name: f'{other[name]} (here: {own[name]})' for name in own
            if name in other and other[name] != own[name]}


def duplicate_due(names: Sequence[str], own: Optional[str], lasted: float,
                  alive: bool = False) -> bool:
    """
    Tell whether a topic's publishers ``names`` (fully qualified node names) are to be reported.

    own: the one node expected to publish (None: any single node); lasted: for how long, s, the
    topic has had more than one publisher; alive: whether there is evidence that a second
    publisher with the expected node's name runs (it announced itself from another process). A
    second publisher with another name is due at once; one with
    the expected name (a restart's dead predecessor, or a second copy) when ``alive``, or once
    it has lasted :data:`DUPLICATE_GRACE` s.
    """
    if len(names) <= 1:
        return False
    expected = own if own is not None else names[0]
    return alive or any(name != expected for name in names) or lasted >= DUPLICATE_GRACE
