# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Figures of a formation run (PNG), in the style of the paper's Fig. 1.

Every function takes a :class:`formation_ros.trajectory.Trajectory` and writes one file; nothing
is computed here that ``core.runs.metrics`` does not provide.
"""

import os

from formation_ros.core.maths.law import beta
from formation_ros.core.runs.metrics import dis_all_series, dis_min_series, formation_errors
from formation_ros.figures.obstacles import draw_3d, draw_plan
import matplotlib
import numpy as np

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402, I100

FIGURES = ('trajectories.png', 'distances.png', 'controls.png', 'formation_error.png')
MAX_PATHS = 200
THICK = 2.2
HEADING_MARKS = 12
"""Bodies drawn along each unicycle's path, at equal intervals of time."""
MAX_HEADING_ROBOTS = 30
DESIRED_COLOR = 'tab:red'
HEADING_COLOR = 'tab:green'
REPULSION_COLOR = 'tab:blue'
FIRST_ROBOT_COLOR = 'k'
REFERENCE_STYLE = {'color': '0.6', 'linestyle': '--', 'linewidth': 1.0}
"""How the reference path q_od is drawn."""
HEADING_SPAN = 0.04
"""Length of a heading arrow, as a fraction of the larger side of the paths' bounding box."""


def polygon(points):
    """Close a polygon: the points (N, dim) and the first one again, (N + 1, dim)."""
    return np.vstack([points, points[:1]])


def shown_robots(num_robots):
    """Return the robots whose paths are drawn (indices): all, or MAX_PATHS spread over N."""
    return np.unique(np.linspace(0, num_robots - 1, min(num_robots, MAX_PATHS)).astype(int))


def robot_color(index):
    """Return the colour of robot ``index`` (0-based): robot 1 black, then the cycle C0, C1, ..."""
    return FIRST_ROBOT_COLOR if index == 0 else f'C{(index - 1) % 10}'


def is_moving(traj):
    """Tell whether the reference centre q_od moves during the run."""
    return bool(np.ptp(traj.q_od, axis=0).max() > 1e-9)


def heading_length(traj):
    """Length of the heading arrows of a run, m (HEADING_SPAN of its paths' extent)."""
    span = max(float(np.ptp(traj.q[..., 0])), float(np.ptp(traj.q[..., 1])), 1e-9)
    return HEADING_SPAN * span


def plot_trajectories(traj, path, title='Trajectories', obstacles=None):
    """Paths, start (o) and end (x) points, the desired formation polygon, the reference path."""
    fig = trajectories_figure(traj, title, obstacles)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def trajectories_figure(traj, title='Trajectories', obstacles=None):
    """
    Return the figure of :func:`plot_trajectories`, not saved.

    obstacles: a ``core.maths.obstacles.Obstacles`` (world frame) drawn under the paths
    (``figures.obstacles``), or None.
    """
    q, desired = traj.q, traj.q_desired
    n = traj.num_robots
    shown = shown_robots(n)
    fig = plt.figure(figsize=(7, 6.5))
    three_d = traj.dim == 3
    ax = fig.add_subplot(111, projection='3d' if three_d else None)
    coords = (lambda pts: (pts[..., 0], pts[..., 1], pts[..., 2])) if three_d else \
        (lambda pts: (pts[..., 0], pts[..., 1]))
    if obstacles is not None and obstacles.count:
        if three_d:
            draw_3d(ax, obstacles, float(q[..., 2].min()), float(q[..., 2].max()))
        else:
            draw_plan(ax, obstacles)
    if is_moving(traj):
        ax.plot(*coords(traj.q_od), **REFERENCE_STYLE, label='reference path q_od')
    for i in shown:
        ax.plot(*coords(q[:, i]), linewidth=THICK if i == 0 else 0.7, color=robot_color(i))
    ax.plot(*coords(polygon(desired[-1])), color=DESIRED_COLOR, linewidth=1.2,
            label='desired formation (end)')
    if traj.heading is not None and traj.q_body is not None:
        _draw_headings(ax, traj, shown)
    ax.scatter(*coords(q[0]), marker='o', s=14, color='tab:blue', label='start')
    ax.scatter(*coords(q[-1]), marker='x', s=24, color='k', label='end')
    if n <= 30:
        for i in range(n):
            ax.text(*coords(q[-1, i]), f' {i + 1}', fontsize=8)
    ax.set_xlabel('x [m]')
    ax.set_ylabel('y [m]')
    if three_d:
        ax.set_zlabel('z [m]')
    else:
        ax.set_aspect('equal', adjustable='datalim')
        ax.grid(True, alpha=0.3)
    what = 'hand points, bodies as arrows, ' if traj.heading is not None else ''
    ax.set_title(f'{title}: N = {n}, {what}robot 1 thick')
    ax.legend(loc='best', fontsize=8)
    fig.tight_layout()
    return fig


def _draw_headings(ax, traj, shown):
    """Arrows from each axle centre along its heading, at HEADING_MARKS times of the run."""
    marks = np.unique(np.linspace(0, len(traj.t) - 1, HEADING_MARKS).astype(int))
    robots = shown[:MAX_HEADING_ROBOTS]
    q_body = traj.q_body[np.ix_(marks, robots)]
    heading = traj.heading[np.ix_(marks, robots)]
    length = heading_length(traj)
    ax.quiver(q_body[..., 0].ravel(), q_body[..., 1].ravel(),
              length * np.cos(heading).ravel(), length * np.sin(heading).ravel(),
              angles='xy', scale_units='xy', scale=1.0, width=0.004, color=HEADING_COLOR,
              label=f'body and heading ({len(marks)} times)')


def plot_distances(traj, law, path):
    """dis_min, dis_all (docs/equations.md, slip 7), ||q_1j||, beta_1j over time (Fig. 1 C, D)."""
    t, q = traj.t, traj.q
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    if traj.num_robots <= 30:
        d1 = np.linalg.norm(q[:, :1, :] - q[:, 1:, :], axis=2)
        top.plot(t, d1, linewidth=0.6, color='0.55')
        bottom.plot(t, beta(d1 ** 2, law), linewidth=0.8)
        bottom.set_title('beta_1j, j = 2..N (eq. 11)')
    else:
        bottom.set_title('beta_1j not drawn for N > 30')
    top.plot(t, dis_min_series(q), color='tab:red', linewidth=1.5, label='dis_min (closest pair)')
    t_all, values = dis_all_series(t, q)
    if len(values):
        top.plot(t_all, values, color='k', linewidth=THICK, label='dis_all (geometric mean)')
    top.axhline(law.repulsion_radius, color=REPULSION_COLOR, linestyle=':', label='b')
    top.set_ylabel('distance [m]')
    top.set_yscale('log')
    top.legend(fontsize=8)
    top.grid(True, alpha=0.3)
    top.set_title('Distances (thin: ||q_1j||)')
    bottom.set_xlabel('t [s]')
    bottom.set_ylim(-0.05, 1.05)
    bottom.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_controls(traj, u_bound, path):
    """Components of u_hat (robot 1 thick, envelope of all robots) against +-c M1 (Fig. 1 B)."""
    t = traj.t
    tracking = is_moving(traj)
    rows = 2 if tracking else 1
    fig, axes = plt.subplots(rows, 1, figsize=(8, 3.6 * rows), sharex=True, squeeze=False)
    series = [('u_hat (bounded, eq. 14)', traj.u_hat)]
    if tracking:
        series.append(('u (world command, eq. 25)', traj.u))
    for ax, (label, values) in zip(axes[:, 0], series):
        envelope = np.max(np.abs(values), axis=(1, 2))
        ax.fill_between(t, -envelope, envelope, color='0.85', label='max |component|, all robots')
        for axis, name in enumerate('xyz'[:traj.dim]):
            ax.plot(t, values[:, 0, axis], linewidth=1.4, label=f'robot 1, {name}')
        ax.set_ylabel(f'{label} [m/s]')
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc='upper right')
    axes[0, 0].axhline(u_bound, color='tab:red', linestyle='--', label='+- c M1')
    axes[0, 0].axhline(-u_bound, color='tab:red', linestyle='--')
    axes[0, 0].legend(fontsize=8, loc='upper right')
    axes[-1, 0].set_xlabel('t [s]')
    axes[0, 0].set_title('Control components')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_unicycle_controls(traj, metrics, path):
    """Plot v and w of every unicycle (robot 1 thick, envelope of all) against bounds (U5)."""
    t, command = traj.t, traj.body_command
    fig, axes = plt.subplots(2, 1, figsize=(8, 7.2), sharex=True)
    rows = [('v [m/s]', 0, metrics['v_bound'], 'sqrt(2) c M1', metrics.get('max_linear'),
             'body.max_linear'),
            ('w [rad/s]', 1, metrics['omega_bound'], 'sqrt(2) c M1 / l',
             metrics.get('max_angular'), 'body.max_angular')]
    for ax, (label, column, bound, bound_name, limit, limit_name) in zip(axes, rows):
        envelope = np.max(np.abs(command[..., column]), axis=1)
        ax.fill_between(t, -envelope, envelope, color='0.85', label='max |value|, all robots')
        ax.plot(t, command[:, 0, column], color='k', linewidth=1.4, label='robot 1')
        for sign in (1.0, -1.0):
            ax.axhline(sign * bound, color='tab:red', linestyle='--',
                       label=f'+- {bound_name}' if sign > 0 else None)
            if limit is not None:
                ax.axhline(sign * limit, color='tab:purple', linestyle=':',
                           label=f'+- {limit_name}' if sign > 0 else None)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc='upper right')
    axes[0].set_title('Unicycle commands (v, w) against their bounds')
    axes[-1].set_xlabel('t [s]')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_formation_error(traj, metrics, path):
    """Largest and mean ||q_i - q_i,desired|| over time, the 0.05 m band and the settle time."""
    errors = formation_errors(traj.q, traj.q_desired)
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(traj.t, np.max(errors, axis=1), color='k', linewidth=1.6, label='max error')
    ax.semilogy(traj.t, np.mean(errors, axis=1), color='tab:blue', linewidth=1.0,
                label='mean error')
    ax.axhline(metrics['settle_tolerance'], color='tab:red', linestyle=':',
               label=f"{metrics['settle_tolerance']} m")
    if metrics.get('settle_time') is not None:
        ax.axvline(metrics['settle_time'], color='tab:green', linestyle='--',
                   label=f"settled at {metrics['settle_time']:.2f} s")
    ax.set_xlabel('t [s]')
    ax.set_ylabel('||q_i - q_i,desired|| [m]')
    ax.set_title('Formation error')
    ax.grid(True, which='both', alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_figures(traj, law, metrics, out_dir, obstacles=None):
    """
    Write the four figures of :data:`FIGURES` into ``out_dir``; returns their paths.

    obstacles: the run's static obstacles (``FormationConfig.obstacles``), drawn on the
    trajectories, or None.
    """
    paths = [os.path.join(out_dir, name) for name in FIGURES]
    plot_trajectories(traj, paths[0], obstacles=obstacles)
    plot_distances(traj, law, paths[1])
    if traj.body_command is not None and 'v_bound' in metrics:
        plot_unicycle_controls(traj, metrics, paths[2])
    else:
        plot_controls(traj, metrics['u_bound'], paths[2])
    plot_formation_error(traj, metrics, paths[3])
    return paths
