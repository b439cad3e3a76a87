# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Another team on a ROS 2 domain: which of the nodes a look found show one, without ROS.

One rule for every looker (docs/faults.md, another team on the domain): a team runs where the
graph lists a ``/clock`` publisher (a plant's or a world's simulated time) or a node named
``plant``, ``relay`` or ``world`` (:data:`HUBS`: one of each per team at most), other than the
looker. The plant looks before its first
state, leaving out itself and a silent ``/clock`` publisher of its own name (what a killed plant
leaves behind); the launcher looks before it starts anything (``tools.domain``). Imports nothing
but the standard library: the launcher's ``--help`` stays light.
"""

from typing import Collection, List, Optional, Sequence

HUBS = ('plant', 'relay', 'world')
"""The names of the nodes a team runs one of: the plant, the relay (a lab) or the world (a
simulated lab, with its relay)."""


def is_hub(name: str) -> bool:
    """Tell whether the fully qualified node ``name`` is a team's hub (any namespace)."""
    return name.rsplit('/', 1)[-1] in HUBS


def occupants(clock_publishers: Sequence[str], nodes: Sequence[str] = (),
              own_name: Optional[str] = None, running: Collection[str] = (),
              sent_clock: bool = False) -> List[str]:
    """
    Return the nodes that show another team on the domain, sorted (empty: none).

    clock_publishers: the ``/clock`` publishers the graph lists, fully qualified, one per writer,
    the looker's own writer left out; nodes: the nodes the graph lists; own_name: the looker's
    name (None: it runs no node of a team, as the launcher); running: the names another process
    announces on ``/diagnostics``; sent_clock: whether ``/clock`` messages came from another
    node. Every ``/clock`` publisher and every plant or relay counts, except the looker's name:
    under it a ``/clock`` publisher counts only when it runs elsewhere (``running``) or
    ``/clock`` was heard, else it is what a killed plant left (DDS forgets it within about
    20 s), and a listed node only when it runs elsewhere (it is the looker itself). Every
    plant, relay or world counts: a world alone (its team not started yet) is a team too.
    """
    found = set()
    for name in clock_publishers:
        if name != own_name or name in running or sent_clock:
            found.add(name)
    for name in nodes:
        if is_hub(name) and (name != own_name or name in running):
            found.add(name)
    return sorted(found)
