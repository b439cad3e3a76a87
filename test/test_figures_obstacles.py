# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The figures and the animation draw the obstacles (figures/obstacles.py): checked on artists."""

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.figures.obstacles import plan_outlines
from formation_ros.figures.plots import trajectories_figure
from formation_ros.figures.scene import Scene
import matplotlib.pyplot as plt
import numpy as np
import pytest

PLANE = Obstacles([1.0, 2.0, 0.5], [-2.0, 0.0, -2.0, 3.0, 0.2], [], 0.3, 2)
SPACE = Obstacles([1.0, 2.0, 0.5], [], [0.0, 0.0, 1.0, 0.7], 0.3, 3)


def straight(dim, samples=11):
    """Two robots moving along x: a Trajectory of ``samples`` samples in ``dim`` D."""
    t = np.linspace(0.0, 1.0, samples)
    q = np.zeros((samples, 2, dim))
    q[:, 0, 0] = np.linspace(-3.0, 3.0, samples)
    q[:, 1, 1] = 4.0
    zeros = np.zeros_like(q)
    return Trajectory(t=t, q=q, u=zeros, u_hat=zeros, q_desired=q[-1:].repeat(samples, 0),
                      q_od=np.zeros((samples, dim)))


def found(ax):
    return [artist for artist in ax.get_children() if artist.get_gid() == 'obstacles']


def test_outlines_are_the_surfaces():
    outlines = plan_outlines(PLANE)
    assert len(outlines) == PLANE.count
    for index, outline in enumerate(outlines):
        distances = PLANE.surface(outline).distances[:, index]
        assert distances == pytest.approx(0.0, abs=1e-9), PLANE.labels()[index]
    sphere = plan_outlines(SPACE)[1]
    assert np.hypot(sphere[:, 0], sphere[:, 1]) == pytest.approx(0.7)


def test_the_trajectories_fill_every_obstacle_in_2d():
    fig = trajectories_figure(straight(2), obstacles=PLANE)
    try:
        (collection,) = found(fig.axes[0])
        assert len(collection.get_paths()) == PLANE.count
        assert 'obstacles' in [text.get_text() for text in fig.axes[0].get_legend().get_texts()]
    finally:
        plt.close(fig)
    bare = trajectories_figure(straight(2))
    try:
        assert found(bare.axes[0]) == []
    finally:
        plt.close(bare)


def test_the_trajectories_outline_pillars_and_wireframe_spheres_in_3d():
    fig = trajectories_figure(straight(3), obstacles=SPACE)
    try:
        artists = found(fig.axes[0])
        wireframes = [a for a in artists if type(a).__name__ == 'Line3DCollection']
        lines = [a for a in artists if type(a).__name__ == 'Line3D']
        assert len(wireframes) == 1
        assert len(lines) == 2 + 4  # the pillar's footprint at two heights, four edges
    finally:
        plt.close(fig)


@pytest.mark.parametrize('dim', [2, 3])
def test_the_animation_draws_them_once_under_the_robots(dim):
    obstacles = PLANE if dim == 2 else SPACE
    scene = Scene(straight(dim), np.full(2, 2.0), 1.0, 0.0, (), 'obstacles', 3.0, obstacles)
    try:
        (collection,) = found(scene.ax)
        assert len(collection.get_paths()) == obstacles.count
        assert collection not in scene.moving
        pixels = scene.render(3, 0, 20)
        assert pixels.shape[2] == 4
    finally:
        scene.close()
