"""Pictures of navigation episodes: the still (`episode_figure`, `jaxplan navigate --out x.png`, the demo's map
panel) and the animation (`animate_episodes`, `jaxplan navigate --out x.gif`, ``demo.gif``).

Both draw in `jaxplan.experiments.style`'s language: the map with its zones, each robot's global plan (dashed)
and executed trajectory, its footprint to scale, the start (green circle) and goal (red star), the walkers as
discs of their true radius with the paths they walked (dashed, light), the legend outside the map.

The still marks where each walker came closest to the (first) robot: the walker's disc and the robot's footprint
at that moment, so the gap it kept can be read off the map. The animation is sized by `style.gif_layout`: the
map's aspect, the robot at least `style.MIN_ROBOT_PX` pixels across; a map too large for that (a long aisle
map such as MovingAI's warehouse-10-20-10-2-1, 161 x 63 m) is followed in a window around the robot, beside an
overview of the whole map with the window outlined. Every frame's title carries its time stamp.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from jaxplan.core.io import atomic_path
from jaxplan.experiments import plots, style

__all__ = ["default_footprint", "draw_episodes", "episode_figure", "gif_figure", "animate_episodes"]

plt = plots.plt


def default_footprint():
    """The footprint of `jaxplan.nav.NavConfig`'s default robot (what `jaxplan navigate` and the demo drive)."""
    from jaxplan.nav import NavConfig

    return NavConfig().dwa.robot.footprint


def _goal_m(ep) -> np.ndarray:
    """The episode's goal (m): its last waypoint (the goal cell's centre), else where it stopped."""
    wp = np.asarray(ep.waypoints, np.float64).reshape(-1, 2)
    return wp[-1] if len(wp) else np.asarray(ep.trajectory, np.float64)[-1, :2]


def _walkers(ep) -> tuple[np.ndarray, np.ndarray]:
    """``(positions [T, M, 2], radii [M])`` of the episode's walkers (padding slots have radius 0)."""
    radii = np.asarray(ep.obstacles.radii, np.float64).reshape(-1)
    pos = np.asarray(ep.obstacle_positions, np.float64).reshape(-1, radii.shape[0], 2)
    return pos, radii


def _draw_plan(ax, grid, plan, colour, suffix: str, many: bool) -> None:
    """An episode's global plan ``[P, 2]`` (cells), dashed under its trajectory; in the robot's colour when
    several robots share the picture."""
    if len(plan):
        pl = grid.centre(np.asarray(plan, np.float64).reshape(-1, 2))
        ax.plot(pl[:, 0], pl[:, 1], **{**style.PLAN, "label": f"global plan{suffix}", "zorder": 2.5,
                                       **({"color": colour} if many else {})})


def draw_episodes(ax, grid, episodes: Mapping[str, Any], *, footprint: Any = None, keepout: Any = None,
                  y_up: bool = False, title: str | None = None, legend: str | None = "below"):
    """Draws ``episodes`` (label -> `jaxplan.nav.Episode`, same start, goal and walkers) on ``ax`` over the map.

    Args:
      ax: matplotlib axes.
      grid: the map the episodes ran on.
      episodes: label -> episode; the first one's start, goal and walkers are drawn.
      footprint: the robot's (`jaxplan.dwa.Disc`/`Rectangle` or a radius, m; default `default_footprint`).
      keepout: the map's keep-out cells (`style.keepout_mask`), hatched.
      y_up: a ROS map's world frame (`plots.plot_map`).
      title: axes title.
      legend: ``"below"``, ``"right"`` or None (no legend: the caller composes one).

    Returns:
      ``ax``.
    """
    if not episodes:
        raise ValueError("draw_episodes needs at least one episode")
    fp = default_footprint() if footprint is None else footprint
    plots.plot_map(ax, grid, title=title, colorbar=False, keepout=keepout, y_up=y_up)
    eps = list(episodes.items())
    for k, (name, ep) in enumerate(eps):
        c = style.robot_colour(k, len(eps))
        mine = "" if len(eps) == 1 else f" ({name})"
        _draw_plan(ax, grid, ep.plan, c, mine, len(eps) > 1)
        tr = np.asarray(ep.trajectory, np.float64)
        ax.plot(tr[:, 0], tr[:, 1], color=c, lw=1.8, zorder=3, label=f"executed: {name} ({ep.reason})")
        style.draw_footprint(ax, tr[-1], fp, color=c, label=f"robot at the end (footprint to scale){mine}")
    ep0 = eps[0][1]
    pos, radii = _walkers(ep0)
    if style.real_walkers(radii).size:
        tr0 = np.asarray(ep0.trajectory, np.float64)
        near = style.closest_approach(tr0, pos)
        style.draw_walkers(ax, pos, radii, at=near, disc_label="walkers at their closest approach (to scale)")
        for i, j in enumerate(style.real_walkers(radii)):
            s = min(int(near[j]), len(tr0) - 1)
            style.draw_footprint(ax, tr0[s], fp, color=style.robot_colour(0, len(eps)), fill=False, alpha=1.0,
                                 label=(f"robot at a walker's closest approach"
                                        f"{'' if len(eps) == 1 else f' ({eps[0][0]})'}") if i == 0 else None)
    style.mark_start_goal(ax, np.asarray(ep0.trajectory, np.float64)[0, :2], _goal_m(ep0))
    if legend is not None:
        style.legend_outside(ax, ncol=3, where=legend)
    return ax


def episode_figure(grid, episodes: Mapping[str, Any], *, footprint: Any = None, keepout: Any = None,
                   y_up: bool = False, title: str | None = None):
    """One still of ``episodes`` (`draw_episodes`) in a figure sized to the map; returns the figure."""
    fig, ax = plt.subplots(figsize=style.map_figsize(grid), constrained_layout=True)
    draw_episodes(ax, grid, episodes, footprint=footprint, keepout=keepout, y_up=y_up, title=title)
    return fig


# ---------------------------------------------------------------------------------------------
# The animation

_MARGIN = {"left": 64, "right": 16, "bottom": 48, "top": 36, "gap": 24, "side": 260}
"""Pixels around the map axes of a GIF frame: tick labels, axis labels, the time stamp, the side column
(legend, and the overview of a followed map)."""
_LEGEND_ROW_PX = 17


def _place(patch, pose: np.ndarray, ax) -> None:
    """Moves a footprint patch (`style.draw_footprint`) to ``pose`` ``(x, y, theta)``."""
    from matplotlib.transforms import Affine2D

    if hasattr(patch, "set_center"):
        patch.set_center((float(pose[0]), float(pose[1])))
    else:
        patch.set_transform(Affine2D().rotate(float(pose[2])).translate(float(pose[0]), float(pose[1]))
                            + ax.transData)


def gif_figure(episodes: Mapping[str, Any], grid, *, footprint: Any = None, keepout: Any = None,
               y_up: bool = False, layout: style.GifLayout | None = None):
    """The figure of a GIF of ``episodes`` and the function that draws a step.

    Returns:
      ``(fig, draw, layout)``: ``draw(step)`` puts each robot (footprint to scale) and its trail, the walkers
      (discs to scale) and the time stamp at control step ``step`` (and moves the window of a followed map);
      ``layout`` is the `style.GifLayout` used (pixels per metre, view, cropped). The figure is
      ``fig.get_size_inches() * style.GIF_DPI`` pixels; its first axes is the map.
    """
    if not episodes:
        raise ValueError("gif_figure needs at least one episode")
    fp = default_footprint() if footprint is None else footprint
    H, W = grid.shape
    res = float(grid.resolution)
    x0, y0 = (float(v) for v in grid.origin)
    bounds = (x0, x0 + W * res, y0, y0 + H * res)
    lay = layout or style.gif_layout((W * res, H * res), style.footprint_size(fp))
    vw, vh = lay.view_px
    m = _MARGIN
    eps = list(episodes.items())
    ep0 = eps[0][1]
    pos, radii = _walkers(ep0)
    n_entries = 4 + 3 * len(eps) + (2 if style.real_walkers(radii).size else 0) + 4  # zones and walls: room
    side_h = n_entries * _LEGEND_ROW_PX
    ov_w = m["side"] - 10
    ov_h = 0
    if lay.cropped:
        ov_h = min(ov_w * H / W, 0.6 * max(vh, 300))
        ov_w = min(ov_w, ov_h * W / H)
        side_h += ov_h + 40
    fig_w = m["left"] + vw + m["gap"] + m["side"] + m["right"]
    fig_h = m["top"] + max(vh, side_h) + m["bottom"]
    dpi = style.GIF_DPI
    fig = plt.figure(figsize=(fig_w / dpi, fig_h / dpi), dpi=dpi)
    top = fig_h - m["top"]
    ax = fig.add_axes((m["left"] / fig_w, (top - vh) / fig_h, vw / fig_w, vh / fig_h))
    side_x = (m["left"] + vw + m["gap"]) / fig_w
    ov = None
    if lay.cropped:
        ov = fig.add_axes((side_x, (top - ov_h) / fig_h, ov_w / fig_w, ov_h / fig_h))
        plots.plot_map(ov, grid, colorbar=False, keepout=keepout, y_up=y_up)
        ov.set_xlabel("")
        ov.set_ylabel("")
        ov.tick_params(labelsize=6, length=2)
        ov.set_title("whole map", fontsize=8)
    plots.plot_map(ax, grid, colorbar=False, keepout=keepout, y_up=y_up)
    ax.tick_params(labelsize=8)
    ax.xaxis.label.set_size(9)
    ax.yaxis.label.set_size(9)
    # walkers: their paths (whole episode, dashed and light) and moving discs at their true radius
    discs, _ = style.draw_walkers(ax, pos, radii, at=0, disc_label="walkers (to scale)")
    style.mark_start_goal(ax, np.asarray(ep0.trajectory, np.float64)[0, :2], _goal_m(ep0))
    robots, trails, dots = [], [], []
    for k, (name, ep) in enumerate(eps):
        c = style.robot_colour(k, len(eps))
        mine = "" if len(eps) == 1 else f" ({name})"
        _draw_plan(ax, grid, ep.plan, c, mine, len(eps) > 1)
        (tr,) = ax.plot([], [], color=c, lw=1.8, zorder=3, label=f"executed: {name}")
        trails.append(tr)
        # above the start and goal markers: the moving robot is what a frame is about
        robots.append(style.draw_footprint(ax, np.asarray(ep.trajectory, np.float64)[0], fp, color=c, alpha=0.9,
                                           zorder=7, label=f"robot (footprint to scale){mine}"))
        if ov is not None:
            (dot,) = ov.plot([], [], "o", color=c, ms=4, mec="k", mew=0.5)
            dots.append(dot)
    window = None
    if ov is not None:
        from matplotlib.patches import Rectangle

        window = Rectangle((x0, y0), *lay.view_m, fill=False, edgecolor="k", lw=1.2, label="window shown")
        ov.add_patch(window)
    handles, labels = ax.get_legend_handles_labels()
    if window is not None:
        handles, labels = handles + [window], labels + ["window shown (left)"]
    fig.legend(handles, labels, loc="upper left", fontsize=8, frameon=False,
               bbox_to_anchor=(side_x, (top - (ov_h + 40 if ov is not None else 0)) / fig_h))
    title = ax.set_title("", fontsize=10, loc="left")
    head = " · ".join(f"{name}: {ep.reason}" for name, ep in eps)
    T = max(len(ep.trajectory) for _, ep in eps)
    period = float(ep0.times[1] - ep0.times[0]) if len(ep0.times) > 1 else 0.2

    def draw(step: int):
        step = int(min(max(step, 0), T - 1))
        for (_, ep), tr, rb in zip(eps, trails, robots, strict=True):
            traj = np.asarray(ep.trajectory, np.float64)
            s = min(step, len(traj) - 1)
            tr.set_data(traj[: s + 1, 0], traj[: s + 1, 1])
            _place(rb, traj[s], ax)
        s = min(step, len(pos) - 1)
        for disc, j in zip(discs, style.real_walkers(radii), strict=True):
            disc.set_center(tuple(pos[s, j]))
        if ov is not None:
            c = np.asarray(ep0.trajectory, np.float64)[min(step, len(ep0.trajectory) - 1)]
            a, b, lo, hi = style.follow_window(c, lay.view_m, bounds)
            ax.set_xlim(a, b)
            ax.set_ylim((lo, hi) if y_up else (hi, lo))
            window.set_xy((a, lo))
            for (_, ep), dot in zip(eps, dots, strict=True):
                p = np.asarray(ep.trajectory, np.float64)[min(step, len(ep.trajectory) - 1)]
                dot.set_data([p[0]], [p[1]])
        title.set_text(f"t = {step * period:6.1f} s of {(T - 1) * period:.1f} s    {head}")
        return fig

    draw(0)
    return fig, draw, lay


def animate_episodes(episodes: Mapping[str, Any], grid, path: str | Path, frames: int = 30, *,
                     footprint: Any = None, keepout: Any = None, y_up: bool = False) -> list[str]:
    """A GIF of ``episodes`` (`jaxplan.nav.Episode` by label) on ``grid`` (`gif_figure`): ``frames`` frames
    evenly spaced over the longest episode, 10 per second (matplotlib's Pillow writer; raises ``ImportError``
    without Pillow). Returns the files written."""
    from matplotlib.animation import PillowWriter

    if frames < 1:
        raise ValueError(f"frames must be >= 1, got {frames}")
    path = Path(path)
    fig, draw, _ = gif_figure(episodes, grid, footprint=footprint, keepout=keepout, y_up=y_up)
    T = max(len(ep.trajectory) for ep in episodes.values())
    idx = np.unique(np.linspace(0, T - 1, frames).round().astype(int))
    path.parent.mkdir(parents=True, exist_ok=True)
    # The writer driven directly: `FuncAnimation.save` renders every frame twice (a draw, then
    # the grab's own savefig), half of this function's time.
    writer = PillowWriter(fps=10)
    try:
        with atomic_path(path) as tmp, writer.saving(fig, str(tmp), dpi=style.GIF_DPI):
            for t in idx:
                draw(int(t))
                writer.grab_frame()
    finally:
        plt.close(fig)
    return [str(path)]
