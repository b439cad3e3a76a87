# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The MJCF world of a formation: a floor and one body per robot at its start, with its heading.

:func:`build_scene` takes a validated :class:`~formation_ros.core.settings.params.FormationConfig`
(its ``num_robots``, ``dim``, ``start`` positions and ``start_headings``, ``body.*``,
``command.frame``, ``world_frame`` and the obstacle map ``obstacles``: static geoms,
``physics.obstacles``) and the world's settings (``world.*``) and returns a
:class:`Scene`: the MJCF text, which ``mujoco.MjModel.from_xml_string`` (or, written as
``world.xml``, ``from_xml_path`` and ``python -m mujoco.viewer --mjcf world.xml``) loads as it is,
and the body model of :mod:`formation_ros.physics.models`. Robot i (1-based) is the body
``robot_<i>``, MuJoCo's world frame is ``world_frame`` (kept in the model as the custom text
``world_frame``), z up.
"""

from dataclasses import dataclass
import os
from typing import Optional, Tuple
from xml.etree import ElementTree

from formation_ros.core.maths.frames import desired_positions
from formation_ros.core.settings.names import robot_name
from formation_ros.core.settings.params import FormationConfig, WorldSettings
from formation_ros.physics.contacts import closest_distance
from formation_ros.physics.models import make_model, Model
from formation_ros.physics.obstacles import add_obstacles
from formation_ros.physics.parts import FLOOR_GROUP, GRAVITY, number, numbers
import numpy as np
from numpy.typing import NDArray

WORLD_FILE = 'world.xml'
FLOOR_BELOW = 1.0
"""A flying team's floor (drawn only) is this far below its lowest start, m."""
CEILING_ABOVE = 1.0
"""A flying team's pillars and walls rise this far above the highest point of its flight, m
(the law takes them as unbounded in z; the geoms cover the volume the team flies in)."""
FLIGHT_SAMPLES = 200
"""The times at which :func:`flight_ceiling` looks at the formation's places."""


@dataclass(frozen=True)
class Scene:
    """
    A formation's world.

    xml: the MJCF text; model: the robots' body model; names: the pose body of robot i at
    entry i - 1 (``robot_<i>``); dim: 2 or 3.
    """

    xml: str
    model: Model
    names: Tuple[str, ...]
    dim: int

    def write(self, directory: str) -> str:
        """Write the scene as ``world.xml`` into ``directory`` (created); return the path."""
        os.makedirs(directory, exist_ok=True)
        path = os.path.join(directory, WORLD_FILE)
        with open(path, 'w', encoding='utf-8') as stream:
            stream.write(self.xml)
        return path


def body_name(index: int) -> str:
    """Return the body name of robot ``index`` (0-based): its name, ``robot_<index + 1>``."""
    return robot_name(index + 1)


def _header(root: ElementTree.Element, world: WorldSettings, world_frame: str) -> None:
    ElementTree.SubElement(root, 'compiler', angle='radian', autolimits='true')
    ElementTree.SubElement(root, 'option', timestep=number(world.timestep),
                           integrator='implicitfast', gravity=numbers((0.0, 0.0, -GRAVITY)))
    custom = ElementTree.SubElement(root, 'custom')
    ElementTree.SubElement(custom, 'text', name='world_frame', data=world_frame)
    visual = ElementTree.SubElement(root, 'visual')
    ElementTree.SubElement(visual, 'global', offwidth='1280', offheight='720')
    asset = ElementTree.SubElement(root, 'asset')
    ElementTree.SubElement(asset, 'texture', name='grid', type='2d', builtin='checker',
                           rgb1='0.85 0.85 0.85', rgb2='0.75 0.75 0.75', width='512',
                           height='512')
    ElementTree.SubElement(asset, 'material', name='grid', texture='grid', texrepeat='1 1',
                           texuniform='true')


def flight_ceiling(config: FormationConfig, start: NDArray[np.float64]) -> float:
    """
    Return the top of a flying team's pillars and walls, m: :data:`CEILING_ABOVE` over its flight.

    The flight: the starts (N, 3) and the places of every shape the team may take
    (``config.vertices`` and the named ``formations.*``) about the reference at
    :data:`FLIGHT_SAMPLES` times over ``config.duration``.
    """
    reference = config.reference()
    shapes = np.concatenate([config.vertices, *config.shapes.values()])
    times = np.linspace(0.0, config.duration, FLIGHT_SAMPLES)
    highest = max(float(np.max(desired_positions(shapes, reference.sample(t))[:, 2]))
                  for t in times)
    return max(highest, float(np.max(start[:, 2]))) + CEILING_ABOVE


def build_scene(config: FormationConfig, world: Optional[WorldSettings] = None) -> Scene:
    """
    Return the :class:`Scene` of ``config`` (which needs its start) with ``world``'s settings.

    world: default ``config.world``, else :class:`WorldSettings` defaults.
    """
    if config.start is None:
        raise ValueError('the scene needs the start positions (a configuration validated for '
                         'formation_sim or the plant)')
    world = world or config.world or WorldSettings()
    start = np.asarray(config.start, dtype=float)
    model = make_model(config.body, config.dim, world, config.command.frame,
                       closest_distance(start)[0])
    headings = (np.zeros(len(start)) if config.start_headings is None
                else np.asarray(config.start_headings, dtype=float))
    root = ElementTree.Element('mujoco', model='formation')
    _header(root, world, config.world_frame)
    worldbody = ElementTree.SubElement(root, 'worldbody')
    ElementTree.SubElement(worldbody, 'light', name='sun', pos='0 0 10', dir='0 0 -1',
                           directional='true')
    floor_z = 0.0 if config.dim == 2 else min(0.0, float(np.min(start[:, 2])) - FLOOR_BELOW)
    ElementTree.SubElement(
        worldbody, 'geom', name='floor', type='plane', size='0 0 0.05', material='grid',
        pos=numbers((0.0, 0.0, floor_z)), contype='0',
        conaffinity=str(FLOOR_GROUP if model.has_floor else 0),
        friction=numbers((world.floor_friction, 0.005, 0.0001)))
    actuators = ElementTree.Element('actuator')
    names = []
    if config.obstacles is not None:
        top = (world.obstacle_height if config.dim == 2
               else flight_ceiling(config, start))
        add_obstacles(worldbody, config.obstacles, floor_z, top)
    for index, (position, heading) in enumerate(zip(start, headings)):
        name = body_name(index)
        names.append(model.add_body(worldbody, name, position, float(heading)))
        model.add_actuators(actuators, name)
    root.append(actuators)
    ElementTree.indent(root)
    return Scene(xml=ElementTree.tostring(root, encoding='unicode') + '\n', model=model,
                 names=tuple(names), dim=config.dim)
