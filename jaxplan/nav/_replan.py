"""In-episode global re-planning: an exact grid distance field, its descent, and the trigger.

A navigation episode is one compiled program, so re-planning around an obstacle that
blocks the global path has to run inside it. The global planners of the papers (an ACO
colony per re-plan) would cost far more than the control step; the in-episode planner
is the exact one instead: a goal distance field over the planning map (8-connected,
no corner cutting, octile step costs — the same graph as `jaxplan.astar`) with the
cells near the blocking discs closed, followed downhill from the robot's cell, and
reduced to the vertices where the move direction changes (every run between two such
vertices is a straight line of free cells, so it needs no line-of-sight check).

The field is a Jacobi relaxation (`lax.while_loop`, a few sweeps per iteration) that
stops when nothing changes. A robot that does not re-plan this step never enters the
loop: under ``vmap`` the loop runs while *any* member needs it and costs nothing on
steps where none does.

`replan_slots` is the re-planning of one episode step: the robots that need a new path get
one of a fixed number of slots per group of episodes, and only those fields are computed.

All functions are pure and shape-static; cells are ``(x, y)``, arrays ``[H, W]`` are
indexed ``[y, x]``.
"""

from __future__ import annotations

import math
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from jaxplan.nav._config import NavConfig
from jaxplan.nav._state import Carry, EpisodeInputs
from jaxplan.nav._tracking import way_clear

__all__ = ["MOVES", "distance_field", "descend", "turn_vertices", "path_blocked", "disc_cells", "replan_slots",
           "group_size"]

MOVES = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))
"""The 8 grid moves ``(dx, dy)``: four straight, then four diagonal."""

_COST = np.asarray([1.0] * 4 + [math.sqrt(2.0)] * 4, np.float32)  # numpy: no device array at import
_SWEEPS_PER_ITERATION = 4  # the convergence test costs about as much as a sweep


def _allowed(free: jnp.ndarray) -> jnp.ndarray:
    """``bool[8, H, W]``: move k from each cell stays on free cells and cuts no corner."""
    H, W = free.shape
    p = jnp.pad(free, 1, constant_values=False)
    at = lambda dx, dy: p[1 + dy:1 + dy + H, 1 + dx:1 + dx + W]  # noqa: E731  at(dx, dy)[y, x] = free[y+dy, x+dx]
    out = []
    for dx, dy in MOVES:
        ok = free & at(dx, dy)
        if dx and dy:
            ok = ok & at(dx, 0) & at(0, dy)
        out.append(ok)
    return jnp.stack(out)


def distance_field(free: jnp.ndarray, goal: jnp.ndarray, active: jnp.ndarray, max_sweeps: int,
                   until: jnp.ndarray | None = None) -> jnp.ndarray:
    """Exact 8-connected distance (cells) from every cell to ``goal`` over ``free`` cells.

    Args:
      free: ``bool[H, W]`` cells a path may use.
      goal: ``i32[2]`` goal cell (x, y).
      active: ``bool`` scalar; an inactive call does no sweep (the field is 0 at the goal, inf elsewhere).
      max_sweeps: static bound on the sweeps (a shortest path of more moves than this is
        reported as unreachable).
      until: optional ``i32[2]`` cell: stop as soon as its distance is final. After k
        sweeps every path of at most k moves has been seen, and a path of more moves is
        longer than k (each move costs >= 1), so a distance <= k is final — the loop
        then costs about as many sweeps as the path has moves, not the map's diameter.

    Returns:
      ``f32[H, W]``: +inf for blocked and unreachable cells (and, with ``until``, for cells
      not yet settled when it stopped: only ``until``'s value is then guaranteed).
    """
    H, W = free.shape
    inf = jnp.float32(jnp.inf)
    at_goal = (jnp.arange(W)[None, :] == goal[0]) & (jnp.arange(H)[:, None] == goal[1]) & free
    d0 = jnp.where(at_goal, 0.0, inf).astype(jnp.float32)

    def sweep(d, allowed):
        p = jnp.pad(d, 1, constant_values=inf)
        best = d
        for k, (dx, dy) in enumerate(MOVES):
            best = jnp.minimum(best, jnp.where(allowed[k], p[1 + dy:1 + dy + H, 1 + dx:1 + dx + W] + _COST[k], inf))
        return best

    def settled(d, i):
        if until is None:
            return jnp.asarray(False)
        return d[until[1], until[0]] <= i.astype(jnp.float32)

    def cond(c):
        d, changed, i = c
        return active & changed & (i < max_sweeps) & ~settled(d, i)

    def body(c):
        d, _, i = c
        # Built inside the loop: a call with ``active`` False must cost nothing.
        allowed = _allowed(free)
        new = d
        for _ in range(_SWEEPS_PER_ITERATION):
            new = sweep(new, allowed)
        return new, jnp.any(new != d), i + _SWEEPS_PER_ITERATION

    d, _, _ = lax.while_loop(cond, body, (d0, jnp.asarray(True), jnp.asarray(0)))
    return d


def descend(field: jnp.ndarray, free: jnp.ndarray, start: jnp.ndarray, length: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Follows ``field`` downhill from ``start``: a shortest path of at most ``length`` moves.

    Returns:
      ``(cells i32[length + 1, 2], n i32)``: the path from ``start`` (slots after the goal
      repeat it) and its number of cells; ``n = 0`` when ``start`` is unreachable.
    """
    H, W = free.shape
    moves = jnp.asarray(MOVES, jnp.int32)

    def is_free(c):  # [..., 2] cells; outside the map is blocked
        ok = (c[..., 0] >= 0) & (c[..., 0] < W) & (c[..., 1] >= 0) & (c[..., 1] < H)
        return ok & free[jnp.clip(c[..., 1], 0, H - 1), jnp.clip(c[..., 0], 0, W - 1)]

    def step(c, _):
        cell, done = c
        x, y = cell[0], cell[1]
        nb = cell[None, :] + moves  # [8, 2]
        side_x = cell[None, :] + moves * jnp.asarray([1, 0])  # the orthogonal cells a diagonal passes
        side_y = cell[None, :] + moves * jnp.asarray([0, 1])
        ok = is_free(nb) & is_free(side_x) & is_free(side_y)
        val = field[jnp.clip(nb[:, 1], 0, H - 1), jnp.clip(nb[:, 0], 0, W - 1)] + _COST
        val = jnp.where(ok, val, jnp.inf)
        k = jnp.argmin(val)
        stop = done | (field[y, x] <= 0.0) | ~jnp.isfinite(val[k])
        nxt = jnp.where(stop, cell, nb[k])
        return (nxt, stop), nxt

    start = start.astype(jnp.int32)
    _, cells = lax.scan(step, (start, jnp.asarray(False)), None, length=length)
    cells = jnp.concatenate([start[None], cells])
    moved = jnp.any(cells[1:] != cells[:-1], axis=-1)
    n = 1 + jnp.sum(moved, dtype=jnp.int32)
    reachable = jnp.isfinite(field[start[1], start[0]])
    return cells, jnp.where(reachable, n, 0)


def turn_vertices(cells: jnp.ndarray, n: jnp.ndarray, size: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The cells of a grid path after which the move direction changes, and its last cell.

    Args:
      cells: ``i32[L, 2]`` path with ``n`` valid cells (``n >= 1``).
      size: static number of output slots.

    Returns:
      ``(points f32[size, 2], m i32)``: the turn cells in order, ending with the path's last
      cell (the start itself is not included); slots after ``m`` repeat the last. A path
      with more turns than ``size`` keeps its first ``size − 1`` turns and the last cell.
    """
    L = cells.shape[0]
    idx = jnp.arange(L)
    d = cells[1:] - cells[:-1]  # [L-1, 2] move into cell i+1
    turn = jnp.concatenate([jnp.any(d[1:] != d[:-1], axis=-1), jnp.zeros(1, bool)])  # cell i+1 is a turn
    keep = jnp.concatenate([jnp.zeros(1, bool), turn]) & (idx < n - 1)
    keep = keep | (idx == n - 1) & (n > 1)
    rank = jnp.cumsum(keep) - 1
    last = cells[jnp.maximum(n - 1, 0)]
    m = jnp.minimum(jnp.sum(keep, dtype=jnp.int32), size)
    slot = jnp.where(keep & (rank < size - 1), rank, size)  # overflow and dropped rows go to a dump slot
    out = jnp.zeros((size + 1, 2), jnp.float32).at[slot].set(cells.astype(jnp.float32))[:size]
    out = jnp.where(jnp.arange(size)[:, None] >= m - 1, last.astype(jnp.float32), out)
    return out, m


def path_blocked(position: jnp.ndarray, waypoints: jnp.ndarray, n: jnp.ndarray, index: jnp.ndarray,
                 centres: jnp.ndarray, reach: jnp.ndarray, distance: jnp.ndarray,
                 velocities: jnp.ndarray | None = None, recede=jnp.inf) -> jnp.ndarray:
    """Whether a disc sits on the next ``distance`` metres of the remaining path.

    Args:
      position: ``[2]`` robot position (m); the remaining path runs from it through
        ``waypoints[index:n]`` (``[K, 2]`` m).
      centres: ``[D, 2]`` disc centres (m); ``reach [D]``: the distance (m) from a centre
        within which the path counts as blocked (disc radius + robot radius + margin).
      distance: look-ahead along the path (m).
      velocities: optional ``[D, 2]`` disc velocities (m/s), with ``recede`` (m/s): a disc
        moving along the segment it is near, in the path's direction, at least this fast is
        going the robot's way and does not block that segment.
    """
    K = waypoints.shape[0]
    j = jnp.arange(K)
    live = (j >= index) & (j < n)
    a = jnp.concatenate([position[None], waypoints[:-1]])  # segment j ends at waypoint j
    a = jnp.where((j == index)[:, None], position[None], a)
    b = waypoints
    seg = jnp.sqrt(jnp.sum((b - a) ** 2, axis=-1))
    start_arc = jnp.cumsum(jnp.where(live, seg, 0.0)) - jnp.where(live, seg, 0.0)
    live = live & (start_arc < distance)
    ab = b - a
    t = jnp.sum((centres[:, None, :] - a[None]) * ab[None], axis=-1) / jnp.maximum(jnp.sum(ab * ab, axis=-1), 1e-12)
    p = a[None] + jnp.clip(t, 0.0, 1.0)[..., None] * ab[None]  # [D, K, 2]
    d = jnp.sqrt(jnp.sum((centres[:, None, :] - p) ** 2, axis=-1))
    near = live[None] & (d < reach[:, None])  # [D, K]
    if velocities is not None:
        along = jnp.sum(velocities[:, None, :] * ab[None], axis=-1) / jnp.maximum(seg, 1e-9)[None]
        rec = jnp.asarray(recede)
        near = near & ~(along >= (rec[:, None] if rec.ndim == 1 else rec))
    return jnp.any(near)


def disc_cells(shape: tuple[int, int], centres: jnp.ndarray, reach: jnp.ndarray, resolution, span: int) -> jnp.ndarray:
    """``bool[H, W]``: cells whose square comes closer than ``reach [D]`` (m) to a disc centre ``[D, 2]`` (m).

    Only the ``(2·span + 1)²`` cells around each centre are tested (``span`` static, cells):
    the cost does not grow with the map. A reach beyond ``span + 0.5`` cells is cut there.
    """
    H, W = shape
    off = jnp.arange(-span, span + 1)
    c = jnp.floor(centres / resolution).astype(jnp.int32)  # [D, 2] cell of each centre
    cx = c[:, 0:1, None] + off[None, None, :]  # [D, 1, w]
    cy = c[:, 1:2, None] + off[None, :, None]  # [D, w, 1]
    half = 0.5 * resolution
    gx = jnp.maximum(jnp.abs((cx + 0.5) * resolution - centres[:, 0, None, None]) - half, 0.0)
    gy = jnp.maximum(jnp.abs((cy + 0.5) * resolution - centres[:, 1, None, None]) - half, 0.0)
    hit = gx ** 2 + gy ** 2 < (reach ** 2)[:, None, None]  # [D, w, w]
    cx, cy = jnp.broadcast_to(cx, hit.shape), jnp.broadcast_to(cy, hit.shape)
    inside = hit & (cx >= 0) & (cx < W) & (cy >= 0) & (cy < H)
    flat = jnp.where(inside, cy * W + cx, H * W)  # misses go to a dump slot
    out = jnp.zeros(H * W + 1, bool).at[flat.reshape(-1)].set(True)
    return out[: H * W].reshape(H, W)


_SPAN = 3
"""Cells around a blocking disc's cell that re-planning examines (reach up to 3.5 cells)."""


def group_size(config: NavConfig, batch: int) -> int:
    """Consecutive episodes of a batch of ``batch`` that share re-planning slots (1 without re-planning)."""
    if not config.replan:
        return 1
    return min(config.replan_group or batch, batch)


def replan_slots(config: NavConfig, free: jnp.ndarray, resolution, c: Carry, inputs: EpisodeInputs,
                 need: jnp.ndarray, centres: jnp.ndarray, reach: jnp.ndarray, anchor: jnp.ndarray,
                 clearance: Callable, stranded: jnp.ndarray) -> tuple[Carry, jnp.ndarray, jnp.ndarray]:
    """Re-plans up to `NavConfig.replan_slots` of the robots with ``need [B, N] > 0`` per group
    of `NavConfig.replan_group` episodes (0: the whole batch is one group).

    ``need`` is 2 for a robot that must re-plan (path blocked, drifted off, stalled) and 1 for
    a detour re-check (`NavConfig.recheck_period`); the 2s take the slots first, and a
    re-check's path replaces the robot's only if it is `NavConfig.recheck_gain` shorter than
    what is left of the current one.

    ``centres [B, N, D, 2]`` / ``reach [B, N, D]``: the discs whose nearby cells are closed.
    ``anchor bool[B, N]`` (with ``clearance(x, y)``, m): robots re-planning after a stall, whose new path begins
    at the centre of the cell they stand in when the straight way from where they stand to its first vertex
    comes closer than ``config.dwa.d_safe`` to the map (`jaxplan.nav._tracking.way_clear`, the whole way). The
    path's runs between its vertices go through free cells from centre to centre; only that first leg starts off
    a centre, and a robot standing beside a door facing a goal beyond it stood there until the time limit
    (room-64-64-8, docs/decisions.md, "Stall and orbit watches").
    ``stranded bool[B, N]``: robots whose current path cannot be kept (stalled, or drifted off it behind a wall).
    When the discs' closed cells leave such a robot no way to its goal, it takes the path that ignores the discs
    (the local planner keeps it off them), instead of keeping one that leads it through a wall: in a maze one
    walker in a corridor closes the only way back, and a robot kept tracking a path beyond a wall into a dead end.
    Only the chosen robots' fields are computed (a gather into fixed slots); robots left over
    try again on the next step. Groups are consecutive episodes, so a device holding whole
    groups computes exactly what one device computes for them. The slots in use are planned
    one after another (a `lax.while_loop` over them alone), not vectorised: under ``vmap``
    every slot ran the relaxation sweeps of the longest one, and a loop over every slot paid
    for each unused one's disc mask and descent (with identical trajectories either way).
    Returns the carry, ``bool[B, N]``: the robots that were attempted, and
    ``bool[B, N]``: those whose path was replaced.
    """
    B, N, K = c.waypoints.shape[:3]
    H, W = free.shape
    G = group_size(config, B)
    Bp = -(-B // G) * G
    Q = min(config.replan_slots, G * N)
    # A partial last group is padded with robots that need nothing: only these gathers grow.
    pad = lambda x: jnp.concatenate([x, jnp.zeros((Bp - B,) + x.shape[1:], x.dtype)]) if Bp > B else x  # noqa: E731
    flat_need = pad(need).reshape(Bp // G, G * N).astype(jnp.int32)
    # The first Q, must-re-plans first.
    _, slot = jax.vmap(lambda n: lax.top_k(n * (G * N) - jnp.arange(G * N), Q))(flat_need)
    slot = (slot + (jnp.arange(Bp // G) * (G * N))[:, None]).reshape(-1)  # [S] robots (flat over [Bp, N])
    take = lambda x: pad(x).reshape((Bp * N,) + x.shape[2:])[slot]  # noqa: E731
    kind = take(need)
    use, check = kind > 0, kind == 1
    state, wp, n_wp, index = take(c.state), take(c.waypoints), take(c.n_wp), take(c.index)

    def one(args):
        need1, check1, state1, wp1, n1, index1, goal_cell1, cen, rch, anchor1, stranded1 = args
        closed = disc_cells((H, W), cen, jnp.where(need1, rch, 0.0), resolution, _SPAN)
        cell = jnp.clip(jnp.floor(state1[:2] / resolution).astype(jnp.int32), 0, jnp.asarray([W - 1, H - 1]))
        plan_free = free & ~closed
        plan_free = plan_free.at[cell[1], cell[0]].set(free[cell[1], cell[0]])  # the robot's own cell stays open

        def plan(open_cells):
            field = distance_field(open_cells, goal_cell1, need1, config.replan_sweeps, until=cell)
            return (field, *descend(field, open_cells, cell, config.replan_cells))

        field, cells, n = plan(plan_free)
        # Stranded, and no way round the discs: the way that ignores them (a second field, only then).
        field, cells, n = lax.cond(stranded1 & need1 & (n <= 1), lambda: plan(free), lambda: (field, cells, n))
        pts, m = turn_vertices(cells, jnp.maximum(n, 1), K)
        # A stalled robot off its cell's centre, the way to the first vertex not clear: via the centre.
        via = anchor1 & (n > 1) & ~way_clear(state1[:2], (pts[0] + 0.5) * resolution, config.dwa.d_safe,
                                             clearance, whole=True)
        shifted = jnp.concatenate([cell[None].astype(pts.dtype), pts[:-1]])
        pts, m = jnp.where(via, shifted, pts), jnp.where(via, jnp.minimum(m + 1, K), m)
        # A re-check keeps the current path unless the new one is clearly shorter: the field's
        # length (the same octile grid metric as the turn-vertex polylines) against what is left.
        new_len = field[cell[1], cell[0]] * resolution
        legs = jnp.sqrt(jnp.sum((wp1[1:] - wp1[:-1]) ** 2, axis=-1))
        j = jnp.arange(1, K)
        left = (jnp.sqrt(jnp.sum((wp1[index1] - state1[:2]) ** 2))
                + jnp.sum(jnp.where((j > index1) & (j < n1), legs, 0.0)))
        better = new_len + config.recheck_gain < left
        return (pts + 0.5) * resolution, m, need1 & (n > 1) & (~check1 | better)

    args = (use, check, state, wp, n_wp, index, take(inputs.goal_cell), take(centres), take(reach),
            take(anchor), take(stranded))
    # Only the slots in use are planned, one after another: a loop over all S slots paid for every unused
    # one's disc mask and descent (a batch of one-episode groups has S = B slots, mostly unused). An unused
    # slot's outputs are never read (`put` masks by ``ok``, which is False for it).
    order = jnp.argsort(~use, stable=True)  # the slots in use first, in slot order
    S = use.shape[0]

    def body(loop):
        i, pts_, m_, ok_ = loop
        k = order[i]
        p1, m1, ok1 = one(jax.tree_util.tree_map(lambda a: a[k], args))
        return i + 1, pts_.at[k].set(p1), m_.at[k].set(m1), ok_.at[k].set(ok1)

    out0 = jax.eval_shape(one, jax.tree_util.tree_map(lambda a: a[0], args))
    init = tuple(jnp.zeros((S,) + o.shape, o.dtype) for o in out0)
    _, pts, m, ok = lax.while_loop(lambda loop: loop[0] < jnp.sum(use), body, (jnp.asarray(0), *init))
    g = take(inputs.goal)
    # The last waypoint is the goal itself.
    pts = jnp.where(jnp.arange(K)[None, :, None] >= m[:, None, None] - 1, g[:, None, :], pts)

    def put(x, new, mask):
        flat = pad(x).reshape((Bp * N,) + x.shape[2:])
        upd = jnp.where(mask.reshape(mask.shape + (1,) * (flat.ndim - 1)), new, flat[slot])
        return flat.at[slot].set(upd).reshape((Bp,) + x.shape[1:])[:B]

    attempted = put(jnp.zeros((B, N), bool), use, use)
    replaced = put(jnp.zeros((B, N), bool), ok, ok)
    c = c._replace(waypoints=put(c.waypoints, pts, ok), n_wp=put(c.n_wp, m, ok),
                   index=put(c.index, jnp.zeros_like(m), ok), replans=put(c.replans, take(c.replans) + 1, ok),
                   origin=put(c.origin, state[:, :2], ok), error=put(c.error, jnp.zeros_like(m, c.error.dtype), ok))
    return c, attempted, replaced
