"""MPPI at scale: ms per optimisation on MPPI-Generic's comparison problem, jaxplan beside jax_mppi.

Run:  nice -n 5 python benchmarks/bench_mppi.py [--samples 128,256,...] [--robots 64] [--repeats 5]

The problem is the one Vlahov et al. (2024, "MPPI-Generic: A CUDA library for stochastic trajectory
optimization") use to compare MPPI implementations (their Table 1 and the comparison code published beside
the paper): a differential drive on an 11 m × 11 m costmap at 0.1 m per cell with three square obstacles
(corners (8, 8), (4, 6), (6, 5) m, sides 0.4, 0.5, 0.3 m), from (1, 1) heading 0 towards the goal (10, 10);
controls (v, ω) within v ∈ [−0.35, 0.5] m/s and |ω| <= 0.5 rad/s, dt = 0.02 s, T = 100 steps (a 2 s
horizon), λ = 1, noise σ = 0.2 on both controls, one iteration per optimisation, K = 128 … 16,384 samples.
Their cost charges every point 5 · (distance to the goal) + 5 · |yaw − goal yaw| + 20 · (0.1 m − distance to
the nearest obstacle) within 0.1 m of one (Nav2's goal, goal-angle and obstacle critics).

What is measured, per K, as the median of >= ``--repeats`` timed calls after a warm-up call (compilation
timed apart, as lowering + XLA compilation of the program; the two implementations' calls alternate, so that
a change in the load of a shared machine reaches both alike):

  jaxplan    `jaxplan.mppi.mppi_control`, the step a navigation episode runs, with its own samplers and
             rollout, and its critics weighted to the problem's cost (`jaxplan_params`): goal weight 5 per
             metre per point, obstacle weight 20 per metre within d_clip = 0.1 m of the map's blocked squares
             (its clearance lookup, ``"bilinear"``, as the paper's bilinear costmap query), and the heading
             charged once at the horizon's end, 5 · T per radian, on the angle to the goal direction (jaxplan's
             goal-heading critic; the paper charges every point on the angle to a goal yaw of 0); every other
             critic, the collision cost and the control cost off. Exact arcs per step (jaxplan's rollout),
             three of the K rows fixed candidates (the mean, braking, turning to the goal), acceleration limits
             set far beyond what one step can use, so that only the paper's velocity box binds.
  jax_mppi   ``jax_mppi.command`` (jax_mppi 0.3.0, the JAX port of pytorch_mppi) with the paper's forward-Euler
             dynamics and the same cost written as its running and terminal cost (`point_cost`, using the same
             jaxplan clearance lookup), plus jax_mppi's own noise cost 0.5·Σ εᵀΣ⁻¹ε, which it has no switch for.

Both are jitted with the same XLA options (the defaults; ``--one-thread``: jaxplan's `one_thread_options`,
as its one-robot `mppi_step` uses) and return the applied control and the warm start of the next call
(jaxplan: the shifted mean sequence; jax_mppi: its state), for one robot and for ``--robots`` robots under
``jax.vmap`` (one PRNG key, start state and warm start per robot; ``--batch map``: under ``jax.lax.map``
instead, the robots one after another in one program). `checks` first shows that both compute the same
thing: the same cost for the same control sequences, a first control that turns towards the goal and a
cheaper mean sequence from the start, and progress towards the goal over 500 closed-loop steps.

jax_mppi is not a dependency of jaxplan: install it at benchmark time (it asks for Python >= 3.12 and, from
its sdist, builds an optional CUDA extension; neither is needed here)::

    pip install jaxtyping
    pip install --no-deps --ignore-requires-python \\
        -C cmake.define.CMAKE_DISABLE_FIND_PACKAGE_CUDAToolkit=ON jax-mppi==0.3.0

Without it the script runs jaxplan alone and says so. Other processes on the cores inflate every figure: the
load average and the CPU steal of the run are printed and saved with the JSON record (`_timing.Record`:
``benchmarks/results/bench_mppi-<UTC date>-<HHMM>-<git short rev>.json``, or ``--json PATH``).
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import statistics
import sys
import time
from pathlib import Path
from typing import Any, Callable

os.environ.setdefault("JAXPLAN_CACHE", "off")  # compile times are compilations, not loads from a disk cache

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import Record, Steal, machine_line  # noqa: E402 (the benchmarks folder is not a package)

from jaxplan.dwa import ClearanceTable, Disc, Unicycle, clearance_table, static_clearance  # noqa: E402
from jaxplan.grid import collision_map, grid_from_array  # noqa: E402
from jaxplan.mppi import MPPIConfig, MPPIParams, default_params, mppi_control, shift, validate_config  # noqa: E402

# The problem (MPPI-Generic's comparison settings).
DT, STEPS, LAMBDA, SIGMA = 0.02, 100, 1.0, 0.2
V_MIN, V_MAX, OMEGA_MAX = -0.35, 0.5, 0.5
SIZE_M, RESOLUTION = 11.0, 0.1
OBSTACLES = ((8.0, 8.0, 0.4), (4.0, 6.0, 0.5), (6.0, 5.0, 0.3))
"""(x, y, side) in metres: squares from (x, y) to (x + side, y + side)."""
START, GOAL = (1.0, 1.0, 0.0), (10.0, 10.0)
GOAL_WEIGHT, HEADING_WEIGHT, OBSTACLE_WEIGHT, MARGIN = 5.0, 5.0, 20.0, 0.1
SAMPLES = (128, 256, 512, 1024, 2048, 4096, 8192, 16384)
ROBOTS = 64
GOAL_RADIUS = 20.0
"""jaxplan's goal critic charges within this distance of the goal only: more than the map's diagonal."""
JAX_MPPI_INSTALL = ("pip install jaxtyping && pip install --no-deps --ignore-requires-python "
                    "-C cmake.define.CMAKE_DISABLE_FIND_PACKAGE_CUDAToolkit=ON jax-mppi==0.3.0")

QUOTED = {
    "mppi_generic": {
        "source": "Vlahov et al. 2024, MPPI-Generic (arXiv:2409.07563); figures from the results table "
                  "published with it (github.com/ACDSLab/mppi-generic-website, assets/data/results.csv): "
                  "mean of 10,000 optimisations (TorchRL: 1,000), same problem",
        "unit": "ms per optimisation (mean)",
        "rows": {
            "MPPI-Generic, RTX 4090 + i9-13900K": {128: 0.123, 1024: 0.131, 2048: 0.146, 4096: 0.170,
                                                  8192: 0.232, 16384: 0.389},
            "MPPI-Generic, GTX 1050 Ti + i9-13900K": {128: 0.201, 1024: 0.429, 2048: 0.837, 4096: 1.468,
                                                     8192: 2.893, 16384: 5.638},
            "MPPI-Generic, Jetson Nano (Tegra X1)": {128: 1.024, 1024: 4.105, 2048: 7.297, 4096: 14.124,
                                                    8192: 28.022, 16384: 56.650},
            "Nav2 MPPI (ROS 2, CPU), i9-13900K": {128: 0.393, 1024: 3.364, 2048: 6.742, 4096: 13.948,
                                                 8192: 29.917, 16384: 62.264},
            "Nav2 MPPI (ROS 2, CPU), Ryzen 5 5600X": {128: 0.615, 1024: 4.752, 2048: 9.500, 4096: 19.583,
                                                     8192: 40.637, 16384: 84.260},
            "TorchRL MPPI, RTX 4090 + i9-13900K": {128: 24.47, 1024: 28.14, 2048: 28.21, 4096: 28.25,
                                                  8192: 28.59, 16384: 28.60},
        },
    },
    "nav2": {
        "source": "nav2_mppi_controller README (ros-navigation/navigation2)",
        "claim": "measured to run at 50+ Hz on a modest Intel processor (4th gen i5)",
        "defaults": "batch_size 1000, time_steps 56, model_dt 0.05 s, iteration_count 1 (the README's "
                    "defaults; it gives no settings for the figure)",
    },
}


# ---------------------------------------------------------------------------------------------
# The problem: map, cost, dynamics


def paper_grid():
    """The 11 m × 11 m map at 0.1 m per cell with the three square obstacles (`jaxplan.grid.GridMap`)."""
    n = int(round(SIZE_M / RESOLUTION))
    free = np.ones((n, n), bool)  # [y, x]
    for x, y, side in OBSTACLES:
        i, j, s = int(round(x / RESOLUTION)), int(round(y / RESOLUTION)), int(round(side / RESOLUTION))
        free[j:j + s, i:i + s] = False
    return grid_from_array(free, resolution=RESOLUTION)


def paper_table() -> ClearanceTable:
    """The map's clearance lookup table (`jaxplan.dwa.clearance_table`)."""
    return clearance_table(collision_map(paper_grid()))


def point_cost(table: ClearanceTable, x: jnp.ndarray, y: jnp.ndarray) -> jnp.ndarray:
    """Cost of points ``x, y [...]`` (m): 5 · distance to the goal + 20 · (0.1 − clearance) within 0.1 m."""
    d = jnp.sqrt((x - GOAL[0]) ** 2 + (y - GOAL[1]) ** 2)
    c = static_clearance(table, x, y, "bilinear")
    return GOAL_WEIGHT * d + OBSTACLE_WEIGHT * jnp.maximum(MARGIN - c, 0.0)


def heading_cost(state: jnp.ndarray) -> jnp.ndarray:
    """5 · T per radian between the heading and the direction to the goal (charged once, at the horizon's end)."""
    dx, dy = GOAL[0] - state[..., 0], GOAL[1] - state[..., 1]
    c, s = jnp.cos(state[..., 2]), jnp.sin(state[..., 2])
    return HEADING_WEIGHT * STEPS * jnp.abs(jnp.arctan2(c * dy - s * dx, c * dx + s * dy))


def euler(state: jnp.ndarray, u: jnp.ndarray) -> jnp.ndarray:
    """The paper's forward-Euler differential drive: ``state [3]`` (x, y, θ), ``u [2]`` (v, ω) -> next state."""
    x, y, th = state[..., 0], state[..., 1], state[..., 2]
    return jnp.stack([x + u[..., 0] * jnp.cos(th) * DT, y + u[..., 0] * jnp.sin(th) * DT, th + u[..., 1] * DT],
                     axis=-1)


def running_cost(table: ClearanceTable, state: jnp.ndarray, u: jnp.ndarray) -> jnp.ndarray:
    """jax_mppi's running cost: the point cost of the state before the step (t = 0 … T − 1)."""
    return point_cost(table, state[..., 0], state[..., 1])


def terminal_cost(table: ClearanceTable, state: jnp.ndarray, u: jnp.ndarray) -> jnp.ndarray:
    """jax_mppi's terminal cost: the end point's cost and the heading cost. With the running cost this charges
    points 0 … T where jaxplan charges 1 … T: the extra start point is the same for every sample, so the softmax
    weights do not see it."""
    return point_cost(table, state[..., 0], state[..., 1]) + heading_cost(state)


def sequence_costs(table: ClearanceTable, state: jnp.ndarray, controls: jnp.ndarray) -> jnp.ndarray:
    """``f32[K]`` the problem's cost of control sequences ``[K, T, 2]`` from ``state [3]`` (Euler rollout, points
    1 … T and the end heading): what both implementations minimise, for the checks."""

    def step(x, u):
        nxt = euler(x, u)
        return nxt, point_cost(table, nxt[..., 0], nxt[..., 1])

    x0 = jnp.broadcast_to(state, (controls.shape[0], 3))
    end, costs = jax.lax.scan(step, x0, jnp.swapaxes(controls, 0, 1))
    return jnp.sum(costs, axis=0) + heading_cost(end)


# ---------------------------------------------------------------------------------------------
# jaxplan


def jaxplan_config(samples: int) -> MPPIConfig:
    """`MPPIConfig` of the problem with K = ``samples``: the paper's velocity box, dt, T, one iteration, one point
    per step. Acceleration limits far above what one 0.02 s step can use (the paper has none); a 1 cm footprint
    and d_safe (a point robot: with the collision cost 0 they only choose the fallback when nothing is
    feasible)."""
    robot = Unicycle(v_min=V_MIN, v_max=V_MAX, omega_max=OMEGA_MAX, accel=1e3, decel=1e3, alpha=1e3,
                     footprint=Disc(0.01))
    return validate_config(MPPIConfig(robot=robot, period=DT, d_safe=0.01, d_clip=MARGIN, goal_radius=GOAL_RADIUS,
                                      samples=samples, steps=STEPS, substeps=1, iterations=1,
                                      clearance="bilinear"))


def jaxplan_params() -> MPPIParams:
    """Critic weights that make jaxplan's cost the problem's: its critics are means over the T points, in [0, 1]
    (goal: distance / goal_radius; obstacle: 1 − min(c, d_clip)/d_clip; goal heading: angle / π)."""
    return default_params(temperature=LAMBDA, noise_v=SIGMA, noise_omega=SIGMA, gamma=0.0, collision=0.0,
                          goal=GOAL_WEIGHT * STEPS * GOAL_RADIUS, obstacle=OBSTACLE_WEIGHT * MARGIN * STEPS,
                          goal_heading=HEADING_WEIGHT * STEPS * math.pi, dynamic=0.0, path_align=0.0,
                          path_follow=0.0, prefer_forward=0.0, constraint=0.0)


def batched(one: Callable, robots: int | None, batch: str, shared: int) -> Callable:
    """``one`` over a leading robot axis of its arguments after the first ``shared`` (``batch``: ``"vmap"``, one
    program over all robots' samples, or ``"map"``, `jax.lax.map`: the robots one after the other), or ``one``
    itself when ``robots`` is None."""
    if robots is None:
        return one
    if batch == "vmap":
        return lambda *args: jax.vmap(one, in_axes=(None,) * shared + (0,) * (len(args) - shared))(*args)
    if batch != "map":
        raise ValueError(f"batch must be 'vmap' or 'map', got {batch!r}")
    return lambda *args: jax.lax.map(lambda xs: one(*args[:shared], *xs), args[shared:])


def jaxplan_program(samples: int, robots: int | None, batch: str = "vmap") -> Callable:
    """``f(table, params, state, mean, key) -> (control, next mean)``: one optimisation (one robot: ``state
    [5]``, ``mean [T, 2]``, a key; ``robots``: each with a leading robot axis, batched as `batched`), not yet
    jitted."""
    config = jaxplan_config(samples)
    goal = jnp.asarray(GOAL, jnp.float32)

    def one(table, params, state, mean, key):
        u, info = mppi_control(table, config, params, state, mean, key, goal)
        return u, shift(info.sequence)

    return batched(one, robots, batch, 2)


def jaxplan_args(table: ClearanceTable, states: np.ndarray, robots: int | None) -> tuple:
    """The arguments of `jaxplan_program`'s function for the start ``states [R, 3]`` (the first alone without
    ``robots``): state (x, y, θ, 0, 0), a zero mean sequence and a key per robot."""
    params = jax.device_put(jaxplan_params())
    n = 1 if robots is None else robots
    st = np.zeros((n, 5), np.float32)
    st[:, :3] = states[:n]
    mean = np.zeros((n, STEPS, 2), np.float32)
    keys = jax.random.split(jax.random.key(0), n)
    if robots is None:
        return table, params, jnp.asarray(st[0]), jnp.asarray(mean[0]), keys[0]
    return table, params, jnp.asarray(st), jnp.asarray(mean), keys


# ---------------------------------------------------------------------------------------------
# jax_mppi


def import_jax_mppi():
    """The ``jax_mppi`` module, or None (with how to install it printed)."""
    try:
        import jax_mppi
    except ImportError as e:
        print(f"jax_mppi is not installed ({e}): running jaxplan alone. Install it with\n  {JAX_MPPI_INSTALL}")
        return None
    return jax_mppi


def jax_mppi_setup(jm, samples: int, states: np.ndarray, robots: int | None, table: ClearanceTable,
                   batch: str = "vmap"):
    """``(f, args)``: jax_mppi's ``command`` on the problem, ``f(table, mppi_state, obs) -> (control, next
    state)``, not yet jitted (robots batched as `batched`), and its arguments for the start ``states [R, 3]``
    (a key per robot)."""
    n = 1 if robots is None else robots
    keys = jax.random.split(jax.random.PRNGKey(0), n)
    cfgs = [jm.create(nx=3, nu=2, noise_sigma=jnp.full(2, SIGMA, jnp.float32), num_samples=samples, horizon=STEPS,
                      lambda_=LAMBDA, u_min=jnp.array([V_MIN, -OMEGA_MAX]), u_max=jnp.array([V_MAX, OMEGA_MAX]),
                      key=keys[i]) for i in range(n)]
    config = cfgs[0][0]

    def one(table, mstate, obs):
        return jm.command(config, mstate, obs, euler, lambda s, u: running_cost(table, s, u),
                          lambda s, u: terminal_cost(table, s, u))

    obs = jnp.asarray(states[:n], jnp.float32)
    if robots is None:
        return one, (table, cfgs[0][1], obs[0])
    stacked = jax.tree.map(lambda *xs: jnp.stack(xs), *[c[1] for c in cfgs])
    return batched(one, robots, batch, 1), (table, stacked, obs)


# ---------------------------------------------------------------------------------------------
# Timing


def start_states(n: int, seed: int = 0) -> np.ndarray:
    """``f32[n, 3]``: the problem's start, then random poses at least 1 m inside the map and 0.3 m from the
    obstacles, random headings."""
    rng = np.random.default_rng(seed)
    table = paper_table()
    out = [START]
    while len(out) < n:
        x, y = rng.uniform(1.0, SIZE_M - 1.0, 2)
        if float(static_clearance(table, jnp.float32(x), jnp.float32(y), "bilinear")) >= 0.3:
            out.append((x, y, rng.uniform(-math.pi, math.pi)))
    return np.asarray(out, np.float32)


def time_programs(programs: list[tuple[Callable, tuple]], repeats: int, budget_s: float, max_repeats: int,
                  options: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """Times programs ``(fn, args)`` side by side: compiles each ``jax.jit(fn, compiler_options=options)`` for
    its ``args`` (timed: lowering + XLA), calls each once untimed, then calls them in turn, one call each per
    round, so that a change in the machine's load reaches all of them alike: at least ``repeats`` rounds, more
    while the rounds so far took under ``budget_s`` per program (at most ``max_repeats``).

    Returns:
      per program ``{"compile_s", "ms" (median), "ms_min", "ms_max", "n", "runs_ms"}``, or ``{"error"}`` for
      one that failed to compile or run (e.g. out of memory at the largest sizes; the others go on).
    """
    out: list[dict[str, Any]] = []
    compiled: list[Callable | None] = []
    for fn, args in programs:
        try:
            t0 = time.perf_counter()
            c = jax.jit(fn, compiler_options=options).lower(*args).compile()
            compile_s = time.perf_counter() - t0
            jax.block_until_ready(c(*args))  # warm-up: first-call allocations, thread pool start-up
            out.append({"compile_s": compile_s, "runs_ms": []})
            compiled.append(c)
        except Exception as e:  # noqa: BLE001 - report it and time the others
            out.append({"error": f"{type(e).__name__}: {str(e).splitlines()[0][:200]}"})
            compiled.append(None)
    live = [i for i, c in enumerate(compiled) if c is not None]
    spent = 0.0
    rounds = 0
    while live and (rounds < repeats or (spent < budget_s * len(live) and rounds < max_repeats)):
        for i in list(live):
            try:
                t = time.perf_counter()
                jax.block_until_ready(compiled[i](*programs[i][1]))
                dt_s = time.perf_counter() - t
            except Exception as e:  # noqa: BLE001
                out[i] = {"compile_s": out[i]["compile_s"], "error": f"{type(e).__name__}: {str(e)[:200]}"}
                live.remove(i)
                continue
            out[i]["runs_ms"].append(1e3 * dt_s)
            spent += dt_s
        rounds += 1
    for row in out:
        ms = row.get("runs_ms")
        if ms:
            row.update(ms=statistics.median(ms), ms_min=min(ms), ms_max=max(ms), n=len(ms))
    return out


# ---------------------------------------------------------------------------------------------
# Checks: both compute the same thing


def checks(jm, samples: int = 1024, loop_steps: int = 500) -> dict[str, Any]:
    """Three checks at K = ``samples`` from the problem's start (tolerances in the returned dict):

    1. Same cost: jaxplan's costs of its own K sampled (clamped) sequences equal `sequence_costs` of the
       same sequences (the cost handed to jax_mppi), relative to the spread of the costs (jaxplan rolls
       out exact arcs, the paper and jax_mppi Euler steps).
    2. Same first decision: from the start (heading 0, the goal at 45° to the left) with a zero mean
       sequence, both first controls turn left (ω > 0) without reversing (v >= 0), and both new mean
       sequences cost less than the zero sequence (`sequence_costs`).
    3. Both make progress in closed loop: ``loop_steps`` receding-horizon steps each (the robot moved by the
       paper's Euler step, each controller warm-started by its own output) bring the robot closer to the
       goal by at least half of what the top speed allows in that time, without touching an obstacle.
    """
    table = paper_table()
    x0 = jnp.asarray(START, jnp.float32)
    state5 = jnp.concatenate([x0, jnp.zeros(2, jnp.float32)])
    config, params = jaxplan_config(samples), jax.device_put(jaxplan_params())
    goal = jnp.asarray(GOAL, jnp.float32)
    zero = jnp.zeros((STEPS, 2), jnp.float32)

    @jax.jit
    def jp_step(state5, mean, key):
        return mppi_control(table, config, params, state5, mean, key, goal)

    u_jp, info = jp_step(state5, zero, jax.random.key(1))
    ours = np.asarray(info.costs, np.float64)
    theirs = np.asarray(jax.jit(sequence_costs)(table, x0, info.controls), np.float64)
    spread = float(np.ptp(theirs))
    cost_diff = float(np.max(np.abs((ours - ours.min()) - (theirs - theirs.min()))))
    base = float(sequence_costs(table, x0, zero[None])[0])
    out: dict[str, Any] = {
        "samples": samples,
        "cost": {"max_abs_diff": cost_diff, "spread": spread, "rel": cost_diff / spread, "tolerance_rel": 0.01,
                 "ok": cost_diff <= 0.01 * spread},
        "first": {"zero_sequence_cost": base, "jaxplan_u": [float(v) for v in u_jp],
                  "jaxplan_new_mean_cost": float(sequence_costs(table, x0, info.sequence[None])[0])},
    }

    def jp_loop(key):
        def body(carry, k):
            x, mean = carry
            u, inf = mppi_control(table, config, params, jnp.concatenate([x, jnp.zeros(2, x.dtype)]),
                                  mean, k, goal)
            return (euler(x, u), shift(inf.sequence)), x

        (x, _), xs = jax.lax.scan(body, (x0, zero), jax.random.split(key, loop_steps))
        return x, jnp.min(static_clearance(table, xs[:, 0], xs[:, 1], "bilinear"))

    end_jp, clear_jp = jax.jit(jp_loop)(jax.random.key(2))
    d0 = float(np.hypot(GOAL[0] - START[0], GOAL[1] - START[1]))
    d_jp = float(np.hypot(GOAL[0] - end_jp[0], GOAL[1] - end_jp[1]))
    out["loop"] = {"steps": loop_steps, "start_distance": d0, "jaxplan_distance": d_jp,
                   "jaxplan_min_clearance": float(clear_jp)}
    ok_first = bool(u_jp[0] >= 0 and u_jp[1] > 0 and out["first"]["jaxplan_new_mean_cost"] < base)
    need = 0.5 * V_MAX * loop_steps * DT  # half the top speed over the loop's time
    out["loop"]["required_progress"] = need
    ok_loop = bool(d0 - d_jp >= need and clear_jp > 0)
    if jm is None:
        out["first"]["ok"] = ok_first
        out["loop"]["ok"] = ok_loop
        return out

    cfg, ms = jm.create(nx=3, nu=2, noise_sigma=jnp.full(2, SIGMA, jnp.float32), num_samples=samples,
                        horizon=STEPS, lambda_=LAMBDA, u_min=jnp.array([V_MIN, -OMEGA_MAX]),
                        u_max=jnp.array([V_MAX, OMEGA_MAX]), key=jax.random.PRNGKey(1))

    def jm_step(mstate, x, shift_it=True):
        return jm.command(cfg, mstate, x, euler, lambda s, u: running_cost(table, s, u),
                          lambda s, u: terminal_cost(table, s, u), shift=shift_it)

    u_jm, st = jax.jit(lambda m, x: jm_step(m, x, False))(ms, x0)
    jm_cost = float(sequence_costs(table, x0, st.U[None])[0])
    out["first"].update(jax_mppi_u=[float(v) for v in u_jm], jax_mppi_new_mean_cost=jm_cost)
    out["first"]["ok"] = bool(ok_first and u_jm[0] >= 0 and u_jm[1] > 0 and jm_cost < base)

    def jm_loop(mstate):
        def body(carry, _):
            x, m = carry
            u, m = jm_step(m, x)
            return (euler(x, u), m), x

        (x, _), xs = jax.lax.scan(body, (x0, mstate), None, length=loop_steps)
        return x, jnp.min(static_clearance(table, xs[:, 0], xs[:, 1], "bilinear"))

    _, ms2 = jm.create(nx=3, nu=2, noise_sigma=jnp.full(2, SIGMA, jnp.float32), num_samples=samples,
                       horizon=STEPS, lambda_=LAMBDA, u_min=jnp.array([V_MIN, -OMEGA_MAX]),
                       u_max=jnp.array([V_MAX, OMEGA_MAX]), key=jax.random.PRNGKey(2))
    end_jm, clear_jm = jax.jit(jm_loop)(ms2)
    d_jm = float(np.hypot(GOAL[0] - end_jm[0], GOAL[1] - end_jm[1]))
    out["loop"].update(jax_mppi_distance=d_jm, jax_mppi_min_clearance=float(clear_jm),
                       ok=bool(ok_loop and d0 - d_jm >= need and clear_jm > 0))
    return out


def print_checks(c: dict[str, Any]) -> None:
    k = c["samples"]
    cost, first, loop = c["cost"], c["first"], c["loop"]
    verdict = {True: "ok", False: "FAILED", None: "not run"}
    print(f"checks at K = {k} from (1, 1) heading 0:")
    print(f"  same cost: |Δ(cost − min cost)| <= {cost['max_abs_diff']:.3g} over K sequences, "
          f"{100 * cost['rel']:.3f} % of their spread {cost['spread']:.1f} (tolerance 1 %): {verdict[cost['ok']]}")
    line = (f"  first control (v, ω), must turn left without reversing: jaxplan ({first['jaxplan_u'][0]:+.3f}, "
            f"{first['jaxplan_u'][1]:+.3f})")
    if "jax_mppi_u" in first:
        line += f", jax_mppi ({first['jax_mppi_u'][0]:+.3f}, {first['jax_mppi_u'][1]:+.3f})"
    print(line)
    line = (f"  cost of the mean sequence: zero {first['zero_sequence_cost']:.1f} -> jaxplan "
            f"{first['jaxplan_new_mean_cost']:.1f}")
    if "jax_mppi_new_mean_cost" in first:
        line += f", jax_mppi {first['jax_mppi_new_mean_cost']:.1f}"
    print(f"{line}: {verdict[first['ok']]}")
    line = (f"  {loop['steps']} closed-loop steps: distance to the goal {loop['start_distance']:.2f} -> jaxplan "
            f"{loop['jaxplan_distance']:.3f} m (min clearance {loop['jaxplan_min_clearance']:.2f} m)")
    if "jax_mppi_distance" in loop:
        line += (f", jax_mppi {loop['jax_mppi_distance']:.3f} m (min clearance "
                 f"{loop['jax_mppi_min_clearance']:.2f} m)")
    print(f"{line}; each must gain >= {loop['required_progress']:.2f} m: {verdict[loop['ok']]}")


# ---------------------------------------------------------------------------------------------
# Report


def speed_rows(results: list[dict[str, Any]], robots: int | None) -> list[list[Any]]:
    """Per K: ``[K, jaxplan 1, jax_mppi 1, ratio, jaxplan R, jax_mppi R, ratio]`` (ms; ratio = jax_mppi / jaxplan,
    above 1: jaxplan faster; None where not measured; the last three only with ``robots``)."""
    cell = {(r["impl"], r["robots"], r["samples"]): r.get("ms") for r in results}
    rows = []
    for k in sorted({r["samples"] for r in results}):
        row: list[Any] = [k]
        for n in (1, robots) if robots else (1,):
            a, b = cell.get(("jaxplan", n, k)), cell.get(("jax_mppi", n, k))
            row += [a, b, b / a if a and b else None]
        rows.append(row)
    return rows


def compile_rows(results: list[dict[str, Any]], robots: int | None) -> list[list[Any]]:
    """Per K: ``[K, jaxplan 1, jax_mppi 1, jaxplan R, jax_mppi R]`` compile seconds (None where not measured; the
    last two only with ``robots``)."""
    cell = {(r["impl"], r["robots"], r["samples"]): r.get("compile_s") for r in results}
    ns = (1, robots) if robots else (1,)
    return [[k, *(cell.get((impl, n, k)) for n in ns for impl in ("jaxplan", "jax_mppi"))]
            for k in sorted({r["samples"] for r in results})]


def check_rows(c: dict[str, Any]) -> list[list[Any]]:
    """The checks as rows ``[check, jaxplan, jax_mppi, criterion, passed]``."""
    cost, first, loop = c["cost"], c["first"], c["loop"]
    u = {impl: first.get(f"{impl}_u") for impl in ("jaxplan", "jax_mppi")}
    return [
        ["same cost of the same K sequences: max |Δ(cost − min)| (% of the spread)", 100 * cost["rel"], None,
         f"<= 1 % of the spread ({cost['spread']:.0f})", cost["ok"]],
        ["first control (v, ω) from the start, zero mean", *(None if u[i] is None else [round(v, 3) for v in u[i]]
                                                             for i in ("jaxplan", "jax_mppi")),
         "turns left (ω > 0), v >= 0", first["ok"]],
        ["cost of the new mean sequence (zero sequence: %.0f)" % first["zero_sequence_cost"],
         first["jaxplan_new_mean_cost"], first.get("jax_mppi_new_mean_cost"), "below the zero sequence's",
         first["ok"]],
        [f"distance to the goal after {loop['steps']} closed-loop steps (m; start {loop['start_distance']:.2f})",
         loop["jaxplan_distance"], loop.get("jax_mppi_distance"),
         f"gains >= {loop['required_progress']:.2f} m, never touches an obstacle", loop["ok"]],
    ]


def markdown(columns: list[str], rows: list[list[Any]]) -> str:
    """A plain markdown table for the terminal (numbers to 2 decimals below 100, whole above)."""
    def show(x: Any) -> str:
        if x is None:
            return "—"
        if isinstance(x, bool):
            return "ok" if x else "FAILED"
        if isinstance(x, float):
            return f"{x:.2f}" if abs(x) < 100 else f"{x:.0f}"
        if isinstance(x, list):
            return "(" + ", ".join(show(v) for v in x) + ")"
        return str(x)

    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(show(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def speed_columns(robots: int | None, batch: str) -> list[str]:
    one = ["K", "jaxplan, 1 robot (ms)", "jax_mppi, 1 robot (ms)", "ratio"]
    if not robots:
        return one
    many = f"{robots} robots" + (", lax.map" if batch == "map" else "")
    return [*one, f"jaxplan, {many} (ms)", f"jax_mppi, {many} (ms)", "ratio"]


def quoted_rows() -> tuple[list[str], list[list[Any]]]:
    """MPPI-Generic's published table as ``(columns, rows)``: implementation and hardware, then ms per K."""
    ks = [128, 1024, 2048, 4096, 8192, 16384]
    rows = [[name, *(vals.get(k) for k in ks)] for name, vals in QUOTED["mppi_generic"]["rows"].items()]
    return ["implementation, hardware (quoted)", *(f"K = {k:,}" for k in ks)], rows


def versions() -> dict[str, str | None]:
    from jaxplan.core.provenance import package_versions

    return package_versions(("jaxplan", "jax", "jaxlib", "numpy", "jax-mppi"))


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", default=",".join(map(str, SAMPLES)), help="comma-separated K values")
    ap.add_argument("--robots", type=int, default=ROBOTS, help="robots of the batched runs (0: none)")
    ap.add_argument("--repeats", type=int, default=5, help="timed calls per cell, at least (median reported)")
    ap.add_argument("--budget", type=float, default=1.0,
                    help="seconds of timed calls per cell before stopping at --repeats")
    ap.add_argument("--max-repeats", type=int, default=50, help="timed calls per cell, at most")
    ap.add_argument("--batch", choices=("vmap", "map"), default="vmap",
                    help="robots of the batched runs under jax.vmap (default) or jax.lax.map (one after another)")
    ap.add_argument("--one-thread", action="store_true",
                    help="compile both with jaxplan's one_thread_options (as its one-robot mppi_step does)")
    ap.add_argument("--no-jax-mppi", action="store_true", help="time jaxplan alone even if jax_mppi is installed")
    ap.add_argument("--no-checks", action="store_true", help="skip the checks")
    ap.add_argument("--json", type=Path, default=None, help="write the JSON record here (default: benchmarks/results/)")
    args = ap.parse_args(argv)
    args.samples = [int(s) for s in args.samples.split(",") if s]
    if args.repeats < 1 or args.max_repeats < args.repeats or not args.samples or min(args.samples) < 4:
        ap.error("need --repeats >= 1, --max-repeats >= --repeats and every K >= 4")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    record = Record("bench_mppi", vars(args))
    steal, t0 = Steal(), time.perf_counter()
    jm = None if args.no_jax_mppi else import_jax_mppi()
    have_jm = jm is not None
    vers = versions()
    load = record.load_avg or [math.nan] * 3
    print(f"machine: {machine_line()}; load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(f"jax {vers['jax']}, jaxlib {vers['jaxlib']}, jaxplan {vers['jaxplan']}, "
          f"jax_mppi {vers['jax-mppi'] or 'not installed'}; devices {[str(d) for d in jax.devices()]}")
    print(f"problem: diff drive, dt {DT} s, T {STEPS}, λ {LAMBDA}, σ {SIGMA}, K {args.samples}, "
          f"robots 1 and {args.robots} ({args.batch})\n")

    check = None
    if not args.no_checks:
        t = time.perf_counter()
        check = checks(jm)
        check["wall_s"] = time.perf_counter() - t
        print_checks(check)
        print(f"  [checks: {check['wall_s']:.0f} s]\n")

    options = None
    if args.one_thread:
        from jaxplan.core.xla import one_thread_options

        options = one_thread_options()
    table_ = paper_table()
    robots = args.robots or None
    states = start_states(max(args.robots, 1))
    results: list[dict[str, Any]] = []
    for k in args.samples:
        for n in (None, robots) if robots else (None,):
            cases = [("jaxplan", jaxplan_program(k, n, args.batch), jaxplan_args(table_, states, n))]
            if have_jm:
                cases.append(("jax_mppi", *jax_mppi_setup(jm, k, states, n, table_, args.batch)))
            timed = time_programs([(fn, fargs) for _, fn, fargs in cases], args.repeats, args.budget,
                                  args.max_repeats, options)
            for (impl, _, _), timing in zip(cases, timed, strict=True):
                row: dict[str, Any] = {"impl": impl, "samples": k, "robots": n or 1, **timing}
                results.append(row)
                shown = f"{row['ms']:.2f} ms (n {row['n']}, compile {row['compile_s']:.1f} s)" if "ms" in row \
                    else row["error"]
                print(f"  K {k:>5}, {n or 1:>2} robot(s), {impl:<8}: {shown}", flush=True)
    load_end = list(os.getloadavg())
    peak_rss_gb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20
    many = args.robots or None

    speed_cols = speed_columns(many, args.batch)
    speed = speed_rows(results, many)
    print("\nms per optimisation (median; ratio = jax_mppi / jaxplan, above 1: jaxplan faster)\n")
    print(markdown(speed_cols, speed))
    record.table("MPPI: ms per optimisation", speed_cols,
                 "one MPPI iteration (sample K sequences of 100 steps of 0.02 s, roll out, cost, weight, update) on "
                 "MPPI-Generic's comparison problem, median of at least "
                 f"{args.repeats} calls after a warm-up, the two implementations' calls alternating; ratio = "
                 "jax_mppi ÷ jaxplan (above 1: jaxplan faster)").extend(speed)
    batch_text = f" {many} robots under `jax.{'lax.map' if args.batch == 'map' else 'vmap'}`, one program." \
        if many else ""
    xla_text = "jaxplan's `one_thread_options`" if args.one_thread else "the default XLA options"
    record.note("jaxplan: `jaxplan.mppi.mppi_control` (the step an episode runs) with its critics weighted to the "
                f"problem's cost; jax_mppi {vers['jax-mppi'] if have_jm else '(not run)'}: `jax_mppi.command` with the "
                f"paper's Euler dynamics and the same cost (see the checks). Both jitted with {xla_text}.{batch_text}"
                f" Load average {load[0]:.1f} at the start and {load_end[0]:.1f} at the end on "
                f"{os.cpu_count()} cores: other work shared them, so the ratios, measured side by side, "
                "compare better than the absolute figures.")
    if args.no_jax_mppi:
        record.note("jax_mppi left out (`--no-jax-mppi`).")
    elif not have_jm:
        record.note(f"jax_mppi was not installed: `{JAX_MPPI_INSTALL}`.")
    compile_cols = ["K", "jaxplan, 1 robot (s)", "jax_mppi, 1 robot (s)"]
    if many:
        compile_cols += [f"jaxplan, {many} robots (s)", f"jax_mppi, {many} robots (s)"]
    compiles = compile_rows(results, many)
    print("\ncompile time (s: lowering + XLA compilation)\n")
    print(markdown(compile_cols, compiles))
    record.table("MPPI: compile time", compile_cols, "lowering + XLA compilation of each program, once per K").extend(
        compiles)
    if check is not None:
        check_cols = ["check (K = 1,024, from (1, 1) heading 0)", "jaxplan", "jax_mppi", "criterion", "passed"]
        record.table("MPPI: the two compute the same thing", check_cols,
                     "the cost handed to jax_mppi against jaxplan's own, and both optimisers from the start").extend(
            check_rows(check))
        record.note("jaxplan rolls out exact arcs, jax_mppi (as the paper) Euler steps: the cost check allows 1 % "
                    "of the spread of the K costs. jaxplan's first control is its fixed turn-towards-the-goal "
                    "candidate (v = 0); jax_mppi adds its noise cost 0.5·Σ εᵀΣ⁻¹ε, which it has no switch for.")
    q_cols, q_rows = quoted_rows()
    record.table("MPPI: published figures (quoted)", q_cols,
                 "quoted, not measured here: ms per optimisation (mean) on the same problem, from the results "
                 "table published with MPPI-Generic (Vlahov et al. 2024)").extend(q_rows)
    record.note(f"Nav2's MPPI controller README (quoted): \"{QUOTED['nav2']['claim']}\"; its defaults: "
                f"{QUOTED['nav2']['defaults']}.")
    print(f"\nmachine: {machine_line()}")
    print(f"load average: start {load[0]:.2f}, end {load_end[0]:.2f}; {steal.summary()}; "
          f"peak memory {peak_rss_gb:.1f} GiB")
    record.extra = {"versions": vers, "load_end": load_end, "peak_rss_gb": peak_rss_gb,
                    "problem": {"dt": DT, "steps": STEPS, "lambda": LAMBDA, "sigma": SIGMA, "v": [V_MIN, V_MAX],
                                "omega_max": OMEGA_MAX, "map_m": SIZE_M, "resolution": RESOLUTION,
                                "obstacles": OBSTACLES, "start": START, "goal": GOAL,
                                "weights": {"goal": GOAL_WEIGHT, "heading": HEADING_WEIGHT,
                                            "obstacle": OBSTACLE_WEIGHT, "margin": MARGIN}},
                    "checks": check, "results": results, "quoted": QUOTED}
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    record.write(args.json)


if __name__ == "__main__":
    main()
