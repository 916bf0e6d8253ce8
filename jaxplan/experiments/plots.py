"""Plot helpers (matplotlib only, Agg backend; no metric logic here).

Everything is drawn in world coordinates (m) with row 0 at the top, as in MovingAI files (a ROS map, with
``y_up=True``, in its world frame: row 0 at the bottom, y up, as RViz shows it):
cell ``(x, y)`` covers ``origin + [x·res, (x + 1)·res] × [y·res, (y + 1)·res]`` and its centre lies at
`GridMap.centre`, ``origin + ((x + 0.5)·res, (y + 0.5)·res)`` (docs/guide/maps-and-scenarios.md#conventions;
``origin`` is ``(0, 0)`` unless
the map has one, as a ROS map does). Each helper draws onto a given ``ax`` and
returns it, so a figure is composed from small calls::

    import matplotlib.pyplot as plt
    import jaxplan as jp
    from jaxplan.experiments.plots import plot_map, plot_paths, plot_pheromone, save_figure

    scene = jp.warehouse_chen2023()
    res = jp.plan(scene.grid, scene.start, scene.goal, planner="iaco", keep_pheromone=True)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    plot_map(a, scene.grid, layer="risk")
    plot_paths(a, scene.grid, [res.path], labels=["iaco"], start=scene.start, goal=scene.goal)
    plot_pheromone(b, scene.grid, res.info["tau"][0])
    save_figure(fig, "figures/iaco.png")

Markers, colours, zones and legends follow `jaxplan.experiments.style` (one visual language for every
picture). The only computations here are reductions for display (pheromone per cell, order
statistics of convergence curves over seeds); metrics come from `jaxplan.metrics`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")  # headless by default; figures are written to files
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap, LogNorm, Normalize
from numpy.typing import ArrayLike

from jaxplan.core.io import atomic_path
from jaxplan.experiments import style
from jaxplan.experiments.style import legend_outside
from jaxplan.grid import GridMap, Neighbours, neighbour_table

__all__ = [
    "LAYERS", "TURN_RULE_LABEL", "figure_legend", "legend_outside", "plot_map", "plot_paths", "plot_pheromone",
    "pheromone_per_cell", "plot_convergence", "convergence_bands", "plot_run", "save_figure",
]

#: Map layers `plot_map` can draw, with their colour maps.
LAYERS: dict[str, str] = {"height": "Greens", "risk": "YlOrBr", "clearance_height": "Blues_r"}
#: Seed bands `plot_convergence` can draw.
BANDS = ("iqr", "sd", "minmax")


# ---------------------------------------------------------------------------------------------
# Map


def _extent(grid: GridMap) -> tuple[float, float, float, float]:
    """``(left, right, bottom, top)`` in world metres for ``imshow`` (row 0 at the top; the origin included)."""
    H, W = grid.shape
    res = float(grid.resolution)
    x0, y0 = (float(v) for v in grid.origin)
    return (x0 + 0.0, x0 + W * res, y0 + H * res, y0 + 0.0)


def _frame(ax: plt.Axes, grid: GridMap, title: str | None, y_up: bool = False) -> None:
    """Limits, equal aspect and labels of a map axes: row 0 at the top, or with ``y_up`` (a ROS map's world
    frame) at the bottom."""
    left, right, bottom, top = _extent(grid)
    ax.set_xlim(left, right)
    ax.set_ylim((top, bottom) if y_up else (bottom, top))
    ax.set_aspect("equal")
    frame = ", map frame" if y_up else ""
    ax.set_xlabel(f"x (m{frame})")
    ax.set_ylabel(f"y (m{frame})")
    if title:
        ax.set_title(title)


def _draw_field(
    ax: plt.Axes, grid: GridMap, data: np.ndarray, cmap: str, label: str, norm: Normalize | None = None,
    colorbar: bool = True, bar_label: str | None = None,
):
    """Draws ``data [H, W]`` (a masked array; masked cells stay transparent) as a colour field; the image is
    labelled ``label``, its colour bar ``bar_label`` (default ``label``: a quantity with its unit)."""
    im = ax.imshow(data, cmap=cmap, norm=norm, extent=_extent(grid), interpolation="nearest")
    im.set_label(label)
    if colorbar:
        plt.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label=bar_label or label)
    return im


def _draw_blocked(ax: plt.Axes, grid: GridMap, keepout: np.ndarray | None = None) -> None:
    """Blocked cells in `style.WALL` grey, free cells (and keep-out cells, drawn as zones) transparent."""
    show = ~np.asarray(grid.free)
    if keepout is not None:
        show &= ~np.asarray(keepout, bool)
    blocked = np.ma.masked_where(~show, np.ones(grid.shape))
    im = ax.imshow(blocked, cmap=ListedColormap([style.WALL]), vmin=0, vmax=1, extent=_extent(grid),
                   interpolation="nearest")
    im.set_label("blocked")


def _layer_data(grid: GridMap, layer: str) -> tuple[np.ndarray, str]:
    """The masked ``[H, W]`` values of ``layer`` on free cells, and its colour-bar label."""
    if layer not in LAYERS:
        raise ValueError(f"layer must be None or one of {tuple(LAYERS)}, got {layer!r}")
    values = np.asarray(getattr(grid, layer), dtype=np.float64)
    hide = ~np.asarray(grid.free)
    if layer == "clearance_height":
        hide = hide | ~np.isfinite(values)  # +inf: no roof, nothing to show
        return np.ma.masked_where(hide, values), "clearance height (m)"
    return np.ma.masked_where(hide, values), "height (m)" if layer == "height" else "risk"


TURN_RULE_LABEL = "right-turn cell (opt_ant must turn right on entering)"
"""Legend text of the cells with chu2024's right-hand rule (`plot_map` with ``show_turn_rule``)."""


def _draw_turn_rule(ax: plt.Axes, grid: GridMap) -> None:
    """Hollow purple squares on the free cells with ``turn_rule == 1``: chu2024's right-hand rule, which opt_ant
    applies to an ant entering such a cell (it must take the move a quarter turn right of its heading)."""
    ys, xs = np.nonzero((np.asarray(grid.turn_rule) == 1) & np.asarray(grid.free))
    if len(xs) == 0:
        return
    c = grid.centre(np.stack([xs, ys], axis=-1))
    # An explicit colour leaves the colour cycle alone: the paths drawn next keep their usual colours.
    ax.plot(c[:, 0], c[:, 1], ls="none", marker="s", ms=6, color="tab:purple", mfc="none", mew=1.2,
            label=TURN_RULE_LABEL)


def _draw_tunnels(ax: plt.Axes, grid: GridMap) -> None:
    """Hatched outlines on the free cells with a finite ``clearance_height`` (chu2024's tunnels: a vehicle passes
    only when it is lower than the headroom), labelled with the headroom range in metres."""
    ch = np.asarray(grid.clearance_height, np.float64)
    ys, xs = np.nonzero(np.isfinite(ch) & np.asarray(grid.free))
    if len(xs) == 0:
        return
    res = float(grid.resolution)
    x0, y0 = (float(v) for v in grid.origin)
    lo, hi = float(ch[ys, xs].min()), float(ch[ys, xs].max())
    label = f"tunnel (headroom {lo:.2f} m)" if lo == hi else f"tunnel (headroom {lo:.2f}-{hi:.2f} m)"
    for j, (x, y) in enumerate(zip(xs, ys, strict=True)):
        ax.add_patch(plt.Rectangle((x0 + x * res, y0 + y * res), res, res, fill=False, hatch="xxx",
                                   edgecolor="tab:cyan", lw=1.0, label=label if j == 0 else None))


def plot_map(
    ax: plt.Axes,
    grid: GridMap,
    layer: str | None = None,
    title: str | None = None,
    *,
    show_turn_rule: bool = False,
    show_tunnels: bool = False,
    colorbar: bool = True,
    keepout: ArrayLike | None = None,
    y_up: bool = False,
) -> plt.Axes:
    """Draws the map in world coordinates (m): blocked cells dark, optionally a layer underneath, and its zones.

    Args:
      ax: matplotlib axes.
      grid: the map (``free bool[H, W]`` and its layers).
      layer: ``None``, ``"height"`` (terrain, m), ``"risk"`` (chen2023's unknown-factor
        intensity, scale from 0) or ``"clearance_height"`` (tunnel/bridge headroom, m; cells
        without a roof, ``+inf``, are left blank), drawn as a colour field over free cells.
      title: axes title.
      show_turn_rule: mark the free cells with ``turn_rule == 1`` (chu2024's right-hand rule)
        with hollow purple squares at their centres (legend label `TURN_RULE_LABEL`).
      show_tunnels: outline, hatched, the free cells with a finite ``clearance_height`` (chu2024's
        tunnels; legend label ``"tunnel (headroom ... m)"``).
      colorbar: add a colour bar for ``layer`` (not when it has no cell to show).
      keepout: ``bool[H, W]`` the cells a Nav2 keep-out mask blocked (`style.keepout_mask`): hatched red, not
        drawn as walls.
      y_up: a ROS map's world frame: row 0 (the image's bottom row) at the bottom, y up, axes "(m, map frame)".

    Speed zones (`GridMap.speed_limit` below 1) are tinted yellow, one legend entry per limit. When a zone is
    drawn, the walls get a legend entry too, so the legend tells walls, keep-out and speed zones apart.

    Returns:
      ``ax``. The layer image has label ``layer``'s colour-bar text, the blocked-cell image
      the label ``"blocked"``.
    """
    if layer is not None:
        data, label = _layer_data(grid, layer)
        # Risk is >= 0: anchor the scale at 0, so a risk-free map reads as "no risk".
        norm = Normalize(vmin=0.0, vmax=float(data.max())) if layer == "risk" and data.count() else None
        _draw_field(ax, grid, data, LAYERS[layer], label, norm=norm, colorbar=colorbar and data.count() > 0,
                    bar_label="risk (Poisson draws per cell)" if layer == "risk" else None)
    ko = None if keepout is None else np.asarray(keepout, bool)
    _draw_blocked(ax, grid, ko)
    zones = style.draw_speed_zones(ax, grid)
    if ko is not None and style.draw_keepout(ax, grid, ko) is not None:
        zones.append(ko)
    if zones:
        style.draw_wall_key(ax, grid)
    if show_turn_rule:
        _draw_turn_rule(ax, grid)
    if show_tunnels:
        _draw_tunnels(ax, grid)
    _frame(ax, grid, title, y_up)
    return ax


def figure_legend(fig: plt.Figure, ncol: int = 1, fontsize: float = 8):
    """One legend for every labelled artist of ``fig``'s axes (each label once), below all panels — clear of
    rotated tick labels. Needs a constrained-layout figure (it makes room for it); returns the legend or None."""
    seen: dict[str, object] = {}
    for ax in fig.axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(lab, h)
    if not seen:
        return None
    return fig.legend(list(seen.values()), list(seen), loc="outside lower center", ncol=ncol, fontsize=fontsize,
                      frameon=False)


# ---------------------------------------------------------------------------------------------
# Paths


def _as_path_list(paths: ArrayLike | Sequence[ArrayLike], lengths: ArrayLike | None) -> list[np.ndarray]:
    """Normalises the accepted path forms to a list of ``f64[L_i, 2]`` arrays (checked)."""
    if isinstance(paths, np.ndarray) or (hasattr(paths, "shape") and hasattr(paths, "dtype")):
        arr = np.asarray(paths)
        if arr.ndim == 2:
            arr = arr[None]  # one path [L, 2]
            if lengths is not None and np.ndim(lengths) == 0:
                lengths = np.reshape(lengths, 1)
        if arr.ndim != 3 or arr.shape[-1] != 2:
            raise ValueError(f"paths must be a list of [L, 2] arrays or an array [P, L, 2], got shape {arr.shape}")
        out = list(arr)
    else:
        out = []
        for i, p in enumerate(paths):
            q = np.asarray(p)
            if q.size == 0:
                q = q.reshape(0, 2)
            if q.ndim != 2 or q.shape[1] != 2:
                raise ValueError(f"paths[{i}] must be an array of points [L, 2] (x, y), got shape {q.shape}")
            out.append(q)
    if lengths is not None:
        n = np.asarray(lengths)
        if n.shape != (len(out),):
            raise ValueError(f"lengths must have one entry per path ({len(out)}), got shape {n.shape}")
        if not np.issubdtype(n.dtype, np.integer):
            raise ValueError(f"lengths must be integers (points per path), got dtype {n.dtype}")
        for i, (q, k) in enumerate(zip(out, n, strict=True)):
            if not 0 <= k <= len(q):
                raise ValueError(f"lengths[{i}] = {int(k)} is outside [0, {len(q)}] (the points available)")
        out = [q[: int(k)] for q, k in zip(out, n, strict=True)]
    for i, q in enumerate(out):
        if np.issubdtype(q.dtype, np.integer) and (q < 0).any():
            # Integer cells are never negative: this is padding (BatchResult.paths pads with -1).
            raise ValueError(f"paths[{i}] holds negative cells (padding?); pass lengths to cut it off")
        if not np.isfinite(q.astype(np.float64)).all():
            raise ValueError(f"paths[{i}] contains NaN or inf coordinates (pass lengths to cut off padding)")
    return [q.astype(np.float64) for q in out]


def _to_metres(points: np.ndarray, grid: GridMap, coords: str) -> np.ndarray:
    """``[..., 2]`` cell coordinates (cell centres at integers) or world metres -> world metres."""
    if coords == "cells":
        return grid.centre(points)
    return points


def plot_paths(
    ax: plt.Axes,
    grid: GridMap,
    paths: ArrayLike | Sequence[ArrayLike],
    labels: Sequence[str] | None = None,
    start: ArrayLike | None = None,
    goal: ArrayLike | None = None,
    *,
    lengths: ArrayLike | None = None,
    coords: str = "cells",
    lw: float = 2.0,
) -> plt.Axes:
    """Draws paths as polylines, with optional start and goal markers.

    Args:
      ax: matplotlib axes (usually after `plot_map`).
      grid: the map (for its resolution and origin).
      paths: a list of ``[L_i, 2]`` arrays, one ``[L, 2]`` array (one path), or an array
        ``[P, L, 2]`` of padded paths with ``lengths`` (numpy or jax arrays; e.g.
        ``BatchResult.paths[i]`` with ``n_cells[i]``, or a smoother's ``points``/``n``). Points are ``(x, y)``;
        integer cells or floats (smoothed / any-angle paths), in cell coordinates where ``(x, y)`` is
        the centre of cell ``(x, y)``, or in world metres with ``coords="m"``. Empty paths
        (failed plans) draw nothing.
      labels: one legend label per path.
      start, goal: ``[2]`` points (same ``coords``), drawn as `style.START` (green circle) and `style.GOAL`
        (red star).
      lengths: ``int[P]`` points to draw of each path (a scalar for one ``[L, 2]`` path);
        the rest is padding and is ignored.
      coords: ``"cells"`` (drawn at ``GridMap.centre(p)``, world metres) or ``"m"`` (drawn as given).
      lw: line width.

    Returns:
      ``ax``; path ``i`` is a `Line2D` whose data are the points in metres.

    Raises:
      ValueError: on a bad shape, a label count that does not match, bad ``lengths``,
        non-finite points that are not cut off by ``lengths``, or an unknown ``coords``.
    """
    if coords not in ("cells", "m"):
        raise ValueError(f"coords must be 'cells' or 'm', got {coords!r}")
    plist = _as_path_list(paths, lengths)
    if labels is not None and len(labels) != len(plist):
        raise ValueError(f"got {len(labels)} labels for {len(plist)} paths")
    for i, p in enumerate(plist):
        q = _to_metres(p, grid, coords)
        if len(q):
            ax.plot(q[:, 0], q[:, 1], lw=lw, label=None if labels is None else labels[i])
    ends = []
    for point, name in ((start, "start"), (goal, "goal")):
        c = None
        if point is not None:
            c = np.asarray(point, dtype=np.float64)
            if c.shape != (2,):
                raise ValueError(f"{name} must be a point (x, y), got shape {c.shape}")
            c = _to_metres(c, grid, coords)
        ends.append(c)
    style.mark_start_goal(ax, *ends)
    if labels is not None or start is not None:
        legend_outside(ax)
    return ax


# ---------------------------------------------------------------------------------------------
# Pheromone


def _valid_edges(
    grid: GridMap, K: int, neighbours: Neighbours | int | None, vehicle_height: float | None
) -> np.ndarray:
    """``bool[C, K]`` allowed moves for a pheromone table with K slots."""
    if neighbours is None:
        if K not in (4, 8, 16):
            raise ValueError(f"tau has K = {K} neighbour slots; expected 4, 8 or 16 (the connectivity)")
        neighbours = K
    if isinstance(neighbours, Neighbours):
        valid = np.asarray(neighbours.valid, dtype=bool)
    else:
        valid = neighbour_table(grid, int(neighbours), vehicle_height).valid
    if valid.shape != (grid.n_cells, K):
        raise ValueError(
            f"tau has {K} neighbour slots per cell, but the neighbour table is {valid.shape} "
            f"(cells, slots) for this {grid.shape[1]}x{grid.shape[0]} map"
        )
    return valid


def pheromone_per_cell(
    grid: GridMap,
    tau: ArrayLike,
    neighbours: Neighbours | int | None = None,
    reduce: str = "max",
    vehicle_height: float | None = None,
) -> np.ndarray:
    """The pheromone on each cell's outgoing allowed edges, reduced to one value per cell.

    Args:
      grid: the map (``H × W`` cells, ``C = H · W``).
      tau: ``f32[C, K]`` pheromone per directed edge (row ``i = y · W + x`` is the cell,
        column k the move ``neighbour_table(...).offsets[k]``), or ``[S, C, K]`` for S
        sub-colonies (reduced together with the edges), as in `jaxplan.BatchResult.tau`
        ``[N, R, S, C, K]`` / ``PlanResult.info["tau"]`` ``[S, C, K]``.
      neighbours: the move table the run used, or its connectivity (4, 8, 16); ``None``
        takes the connectivity from K.
      reduce: ``"max"`` or ``"sum"`` over the allowed edges.
      vehicle_height: as the planner's (opt_ant: 0.5), to drop moves into low tunnels.

    Returns:
      ``f64[H, W]``, NaN on cells without allowed moves (blocked or enclosed).
      Disallowed edges never contribute, whatever their stored value.
    """
    t = np.asarray(tau, dtype=np.float64)
    if t.ndim == 2:
        t = t[None]
    if t.ndim != 3:
        raise ValueError(f"tau must be [C, K] or [S, C, K] (pheromone per directed edge), got shape {t.shape}")
    if t.shape[1] != grid.n_cells:
        raise ValueError(
            f"tau has {t.shape[1]} cells, but the {grid.shape[1]}x{grid.shape[0]} map has {grid.n_cells} "
            f"(tau shape {t.shape}; expected [C, K] or [S, C, K])"
        )
    if reduce not in ("max", "sum"):
        raise ValueError(f"reduce must be 'max' or 'sum', got {reduce!r}")
    valid = _valid_edges(grid, t.shape[2], neighbours, vehicle_height)
    v = t[:, valid]  # [S, allowed edges]
    if not np.isfinite(v).all():
        raise ValueError("tau holds NaN or inf on allowed edges")
    if (v < 0).any():
        raise ValueError("tau must be >= 0 on allowed edges")
    masked = np.where(valid[None], t, 0.0 if reduce == "sum" else -np.inf)
    per_cell = masked.max(axis=(0, 2)) if reduce == "max" else masked.sum(axis=(0, 2))
    per_cell = np.where(valid.any(axis=1), per_cell, np.nan)
    return per_cell.reshape(grid.shape)


def plot_pheromone(
    ax: plt.Axes,
    grid: GridMap,
    tau: ArrayLike,
    neighbours: Neighbours | int | None = None,
    reduce: str = "max",
    log: bool = True,
    *,
    vehicle_height: float | None = None,
    title: str | None = None,
    cmap: str = "magma",
    colorbar: bool = True,
    y_up: bool = False,
) -> plt.Axes:
    """Heat map of the final pheromone per cell, with blocked cells on top.

    Args:
      ax: matplotlib axes.
      grid: the map.
      tau: ``f32[C, K]`` or ``[S, C, K]`` pheromone per directed edge (see `pheromone_per_cell`).
      neighbours: the run's `Neighbours` table or connectivity; ``None``: from K.
      reduce: ``"max"`` or ``"sum"`` over each cell's allowed outgoing edges.
      log: logarithmic colour scale (`LogNorm` over the positive values; the image data
        stay linear). Cells whose value is 0 are then left blank.
      vehicle_height: as the planner's, so moves into tunnels too low are not counted.
      title: axes title.
      cmap: colour map.
      colorbar: add a colour bar.
      y_up: a ROS map's world frame, as `plot_map`.

    Returns:
      ``ax``; the heat map is the `AxesImage` labelled ``"pheromone"`` whose data are the
      ``[H, W]`` values of `pheromone_per_cell` (masked where NaN).

    Raises:
      ValueError: tau of the wrong shape for the map or neighbour table, negative or
        non-finite values on allowed edges, an unknown ``reduce``.
    """
    field = pheromone_per_cell(grid, tau, neighbours, reduce, vehicle_height)
    data = np.ma.masked_invalid(field)
    norm = None
    if log:
        pos = field[np.isfinite(field) & (field > 0)]
        if pos.size:
            norm = LogNorm(vmin=pos.min(), vmax=pos.max())
    label = f"pheromone ({reduce} over edges{', log scale' if log else ''})"
    bar = f"pheromone τ (dimensionless; {reduce} over edges{', log scale' if log else ''})"
    im = _draw_field(ax, grid, data, cmap, label, norm=norm, colorbar=colorbar, bar_label=bar)
    im.set_label("pheromone")
    _draw_blocked(ax, grid)
    _frame(ax, grid, title, y_up)
    return ax


# ---------------------------------------------------------------------------------------------
# Convergence


def convergence_bands(history: ArrayLike, band: str = "iqr") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Centre line and band of best-cost curves over seeds, ignoring runs without a path yet.

    Args:
      history: ``[R, I]`` best cost after each iteration of R runs (seeds), or ``[I]``
        for one run. ``inf`` or NaN means the run has no path yet.
      band: ``"iqr"`` (median, 25th–75th percentile), ``"sd"`` (mean ± sample standard
        deviation; 0 with one run) or ``"minmax"`` (median, min–max).

    Returns:
      ``(centre, low, high, found)``: ``f64[I]`` each, computed at each iteration over the
      runs with a finite cost only (NaN where none has one); ``found`` ``int[I]`` how many.
      Early iterations therefore summarise the runs that have already succeeded.
    """
    h = np.asarray(history, dtype=np.float64)
    if h.ndim == 1:
        h = h[None]
    if h.ndim != 2:
        raise ValueError(f"history must be [R, I] (runs, iterations) or [I], got shape {h.shape}")
    if band not in BANDS:
        raise ValueError(f"band must be one of {BANDS}, got {band!r}")
    ok = np.isfinite(h)
    found = ok.sum(axis=0)
    I = h.shape[1]
    centre, low, high = (np.full(I, np.nan) for _ in range(3))
    cols = np.nonzero(found > 0)[0]
    for t in cols:  # per column: each iteration has its own set of finite runs
        v = h[ok[:, t], t]
        if band == "sd":
            m = v.mean()
            s = v.std(ddof=1) if len(v) > 1 else 0.0
            centre[t], low[t], high[t] = m, m - s, m + s
        elif band == "iqr":
            centre[t], low[t], high[t] = np.quantile(v, [0.5, 0.25, 0.75])
        else:
            centre[t], low[t], high[t] = np.median(v), v.min(), v.max()
    return centre, low, high, found


def _histories(history, labels: Sequence[str] | None) -> tuple[list[np.ndarray], list[str | None]]:
    """``[R, I]`` array / dict name -> array / list of arrays -> (arrays, labels)."""
    if isinstance(history, Mapping):
        arrays, names = list(history.values()), [str(k) for k in history]
        if labels is not None:
            if len(labels) != len(names):
                raise ValueError(f"got {len(labels)} labels for {len(names)} histories")
            names = list(labels)
        return arrays, names
    if isinstance(history, (list, tuple)) and len(history) and np.ndim(history[0]) == 2:
        arrays = list(history)
    else:
        arrays = [history]
    if labels is not None and len(labels) != len(arrays):
        raise ValueError(f"got {len(labels)} labels for {len(arrays)} histories")
    return arrays, list(labels) if labels is not None else [None] * len(arrays)


def plot_convergence(
    ax: plt.Axes,
    history: ArrayLike | Mapping[str, ArrayLike] | Sequence[ArrayLike],
    labels: Sequence[str] | None = None,
    band: str | None = "iqr",
    x: ArrayLike | None = None,
    *,
    ylabel: str = "best cost",
    alpha: float = 0.25,
    colors: Sequence[str] | None = None,
) -> plt.Axes:
    """Convergence curves (best cost per iteration) with a band over seeds.

    Args:
      ax: matplotlib axes.
      history: one planner's ``[R, I]`` curves (R seeds, I iterations; ``[I]`` for one run),
        e.g. ``BatchResult.history[i]``, or several planners as a dict name -> ``[R, I]``
        or a list of ``[R, I]`` arrays (their I may differ).
      labels: one legend label per planner (default: the dict keys; none for arrays).
      band: ``"iqr"`` (median line, 25–75 % band), ``"sd"`` (mean line, ± one standard
        deviation), ``"minmax"`` (median line, min–max band) or ``None`` (line only).
      x: ``[I]`` x values (default: iteration numbers 1..I, history[t] being the best
        cost after iteration t + 1).
      ylabel: y axis label.
      alpha: band opacity.
      colors: one matplotlib colour per planner (default: the axes' colour cycle), so that a planner
        keeps its colour across panels.

    Returns:
      ``ax``. Per planner, one line (label as given) and, unless ``band is None``, one
      ``fill_between`` band. Runs that have not found a path yet (``inf``/NaN cost) are
      left out of the statistics at that iteration (`convergence_bands`); iterations at
      which no run has a path are not drawn (gaps in line and band).

    Raises:
      ValueError: a history that is not ``[R, I]``, ``x`` of the wrong length, label or colour
        count mismatch, unknown ``band``.
    """
    if band is not None and band not in BANDS:
        raise ValueError(f"band must be one of {BANDS} or None, got {band!r}")
    arrays, names = _histories(history, labels)
    if colors is not None and len(colors) != len(arrays):
        raise ValueError(f"got {len(colors)} colors for {len(arrays)} histories")
    for i, (h, name) in enumerate(zip(arrays, names, strict=True)):
        centre, low, high, _ = convergence_bands(h, band or "iqr")
        I = len(centre)
        xs = np.arange(1, I + 1) if x is None else np.asarray(x, dtype=np.float64)
        if xs.shape != (I,):
            raise ValueError(f"x must have one value per iteration ({I}), got shape {xs.shape}")
        (line,) = ax.plot(xs, centre, lw=1.8, label=name, **({} if colors is None else {"color": colors[i]}))
        if band is not None:
            draw = np.isfinite(low) & np.isfinite(high)
            ax.fill_between(xs, low, high, where=draw, color=line.get_color(), alpha=alpha, lw=0, interpolate=False)
    ax.set_xlabel("iteration (count)")
    ax.set_ylabel(ylabel)
    if any(n is not None for n in names):
        ax.legend(fontsize=8)
    return ax


# ---------------------------------------------------------------------------------------------
# Figure-level convenience and output


def plot_run(
    grid: GridMap,
    result,
    start: ArrayLike | None = None,
    goal: ArrayLike | None = None,
    layer: str | None = None,
    neighbours: Neighbours | int | None = None,
    vehicle_height: float | None = None,
) -> plt.Figure:
    """One ACO run at a glance: map and path, pheromone (if kept), convergence.

    Args:
      grid: the map.
      result: a `jaxplan.PlanResult` (``info["tau"]`` is drawn when the planner ran with
        ``keep_pheromone=True``; its S sub-colonies are reduced together).
      start, goal: cells to mark (default: the path's ends).
      layer: map layer under the path (see `plot_map`).
      neighbours, vehicle_height: as for `plot_pheromone` (opt_ant: ``vehicle_height=0.5``).

    Returns:
      A figure with two or three axes; write it with `save_figure` and close it.
    """
    tau = result.info.get("tau") if isinstance(result.info, Mapping) else None
    n = 3 if tau is not None else 2
    fig, axes = plt.subplots(1, n, figsize=(5 * n, 4.2), constrained_layout=True)
    path = np.asarray(result.path)
    if start is None and len(path):
        start = path[0]
    if goal is None and len(path):
        goal = path[-1]
    plot_map(axes[0], grid, layer=layer, title=f"{result.planner}: {result.length:.2f} m")
    plot_paths(axes[0], grid, [path], labels=[result.planner], start=start, goal=goal)
    if tau is not None:
        plot_pheromone(axes[1], grid, tau, neighbours, vehicle_height=vehicle_height, title="final pheromone")
    plot_convergence(axes[-1], np.asarray(result.history)[None], band=None)
    axes[-1].set_title("convergence")
    return fig


def save_figure(fig: plt.Figure, path: str) -> list[str]:
    """Writes ``path`` (its suffix decides the format) atomically; returns the files written."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=150, bbox_inches="tight")
    return [str(p)]
