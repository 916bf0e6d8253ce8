"""DWA local-planner speed: trajectory points per second and milliseconds per control step, JAX vs numpy.

Run:  python benchmarks/bench_dwa.py [--repeat 9] [--robots 1,64,1024]

Scene: a 48 m x 32 m warehouse (`jp.WarehouseGenerator`, 0.5 m per cell, 1.5 m aisles).
Robots stand on random free cells (clearance >= 0.5 m) with random headings, speeds in
[0, 1.2] m/s and yaw rates in [-2, 2] rad/s, each with a sub-goal a few metres away.
One control step = the default configuration of cui2025: 20 x 40 velocity samples,
each rolled out for 20 steps of 0.1 s (16,000 trajectory points per robot), weighted
evaluator, argmax; every point's clearance is looked up (``hybrid``: exact below 1.5
cells; a second row uses the plain ``bilinear`` interpolation).

For 1, 64 and 1,024 robots it prints:
  * JAX: milliseconds per control step of the compiled core (`dwa_control` for one
    robot, `dwa_control_batch` for a batch; rollouts not kept, as in an episode) and
    millions of trajectory points per second, each the median of ``--repeat`` runs;
  * numpy: the same step (same window, samples, exact-arc rollouts, hybrid clearance
    tables, critics and selection) vectorised over all robots and samples with a Python
    loop over the 20 steps — and the ratio; its chosen samples are compared with JAX's;
  * compile time of each compiled program (trace + XLA);
  * for batches over 128 robots, a second hybrid row with ``chunk=None``: one vmap over the
    whole batch instead of `dwa_control_batch`'s default chunks of 128 (faster to compile,
    slower to run on a CPU);
  * for one robot: the step inside a compiled 50-step closed-loop episode (`lax.scan` of
    `dwa_control` and `advance`, as the navigation episodes run it: no per-call dispatch)
    and the host front `dwa_step` (validation, every rollout kept and copied to numpy);
  * for one robot on PythonRobotics' own DWA scenario (PathPlanning/DynamicWindowApproach: its
    15 point obstacles, start (0, 0, π/8, 0, 0), goal (10, 10)): the Python-facing step from
    `make_stepper`, `dwa_step(full_info=False)` and `dwa_step`, beside the same step inside a
    compiled 50-step episode and beside PythonRobotics' own `dwa_control` on its own config, in
    the same process; and the stepper's path with its program compiled as XLA does by default
    (``split``: large loops split across XLA's intra-op threads, which the stepper's program
    skips), in rounds interleaved with the stepper's. Its obstacles become blocked cells of 0.25
    m centred on the points (a map with origin (-5.125, -5.125) m and 5 m of free margin round
    them); jaxplan's robot and window stay cui2025's defaults (20 x 40 samples x 20 steps =
    16,000 trajectory points; PythonRobotics' config samples its window every 0.01 m/s and
    0.1°/s over a 3 s horizon: the table prints its points per call). PythonRobotics' source is
    MIT-licensed and is not part of jaxplan: point ``PYTHONROBOTICS_DIR`` at a checkout of
    https://github.com/AtsushiSakai/PythonRobotics (or at the file itself); without it its row
    is skipped with a message.
Each measurement runs in a child process, twice: with XLA's default threads and pinned
to one core (on a 2-core machine XLA's intra-op threads help big batches but cost a
single robot), and once more with the batch sharded over two XLA host devices
(``--xla_force_host_platform_device_count=2``, one thread each). Other processes share
the cores, so figures vary by tens of percent from run to run; compare medians. The tables also go to a JSON record
in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import subprocess
import sys
import time

import numpy as np
from _timing import Record, Steal, blocking, machine_line, median_time

# ---------------------------------------------------------------------------------------------
# The numpy version of one step (same maths as jaxplan.dwa, vectorised over robots and samples).


def numpy_step(quads, res, shape, states, goals, cfg, pad):
    """Controls ``[B, 2]`` and chosen indices ``[B]``; ``quads`` are the hybrid tables (numpy)."""
    r = cfg.robot
    H, W = shape
    P, dt, T = cfg.period, cfg.dt, cfg.steps
    v0, w0 = states[:, 3], states[:, 4]

    def interval(cur, down, up, lo_lim, hi_lim):
        lo, hi = np.maximum(cur - down, lo_lim), np.minimum(cur + up, hi_lim)
        only = np.clip(np.clip(cur, lo_lim, hi_lim), cur - down, cur + up)
        empty = lo > hi
        return np.where(empty, only, lo), np.where(empty, only, hi)

    v_lo, v_hi = interval(v0, r.decel * P, r.accel * P, r.v_min, r.v_max)
    w_lo, w_hi = interval(w0, r.alpha * P, r.alpha * P, -r.omega_max, r.omega_max)
    k = np.arange(cfg.samples)
    t_v = ((k // cfg.n_omega) / (cfg.n_v - 1)).astype(np.float32)
    t_w = ((k % cfg.n_omega) / (cfg.n_omega - 1)).astype(np.float32)
    V = (v_lo[:, None] + t_v * (v_hi - v_lo)[:, None]).astype(np.float32)  # [B, S]
    Wm = (w_lo[:, None] + t_w * (w_hi - w_lo)[:, None]).astype(np.float32)
    x0, y0, th0 = states[:, :1], states[:, 1:2], states[:, 2:3]
    phi = Wm * (dt / 2)
    small = np.abs(phi) < 1e-4
    rot = np.exp(1j * phi).astype(np.complex64)
    arc_scale = V * dt / np.where(small, 1.0, phi)
    e0 = np.exp(1j * th0).astype(np.complex64)
    inv = np.float32(1.0 / res)
    Wp = W + 2 * pad
    bits_shift = [(m % 2) + 2 * (n % 2) for n in range(4) for m in range(4)]
    roles = [(m >= 2) + 2 * (n >= 2) for n in range(4) for m in range(4)]

    def clearance(x, y):
        u = np.clip(x * inv - 0.5, -1.0, float(W))
        v = np.clip(y * inv - 0.5, -1.0, float(H))
        fu, fv = np.floor(u), np.floor(v)
        a, b = u - fu, v - fv
        idx = ((fv + pad) * Wp + (fu + pad)).astype(np.int32)
        q = [quads[i][idx] for i in range(4)]
        bil = (1 - a) * (1 - b) * q[0] + a * (1 - b) * q[1] + (1 - a) * b * q[2] + a * b * q[3]
        bits = [qq.view(np.int32) for qq in q]
        gx = (a + 0.5, np.maximum(a - 0.5, 0), np.maximum(0.5 - a, 0), 1.5 - a)
        gy = (b + 0.5, np.maximum(b - 0.5, 0), np.maximum(0.5 - b, 0), 1.5 - b)
        best = np.full(a.shape, 1e6, np.float32)
        for n in range(4):
            f = [(bits[roles[4 * n + m]] >> bits_shift[4 * n + m]) & 1 for m in range(4)]
            left = np.where(f[1] != 0, gx[1], np.where(f[0] != 0, gx[0], 1e6))
            right = np.where(f[2] != 0, gx[2], np.where(f[3] != 0, gx[3], 1e6))
            g = np.minimum(left, right)
            best = np.minimum(best, g * g + gy[n] * gy[n])
        near = np.sqrt(np.maximum(best, 1e-12))
        far = np.minimum(near, np.maximum(bil, 1.5))
        return np.where(near < 1.5, near, far) * res

    q = rot.copy()
    m = np.full(V.shape, np.inf, np.float32)
    for step in range(1, T + 1):
        arc = np.where(small, V * (step * dt), arc_scale * q.imag)
        p = e0 * q * arc
        m = np.minimum(m, clearance(x0 + p.real, y0 + p.imag))
        q = q * rot
    q = q * np.conj(rot)
    arc = np.where(small, V * (T * dt), arc_scale * q.imag)
    p = e0 * q * arc
    ex, ey = x0 + p.real, y0 + p.imag
    h = e0 * q * q
    feasible = m >= cfg.d_safe
    # Critics (weighted evaluator, normalised by the feasible mean floored at 0.25).
    dx, dy = goals[:, :1] - ex, goals[:, 1:] - ey
    cross, dot = h.real * dy - h.imag * dx, h.real * dx + h.imag * dy
    at_goal = dx * dx + dy * dy < 1e-12
    err = np.abs(np.where(at_goal, 0.0, np.arctan2(cross, np.where(at_goal, 1.0, dot))))
    G = 1 - err / np.pi
    Vc = np.clip((V - r.v_min) / (r.v_max - r.v_min), 0, 1)
    O = np.clip(m, 0, cfg.d_clip) / cfg.d_clip
    reach = max(abs(r.v_min), r.v_max) * T * dt
    d_end = np.sqrt(np.maximum(dx * dx + dy * dy, 1e-12))
    d0 = np.sqrt(np.maximum(np.sum((states[:, :2] - goals) ** 2, axis=1, keepdims=True), 1e-12))
    D = np.clip(1 - d_end / (d0 + reach), 0, 1)
    f = feasible + 1e-6
    score = np.zeros(V.shape, np.float32)
    for c, wgt in ((G, 0.4), (Vc, 0.3), (O, 0.3), (D, 0.0)):
        mean = np.maximum(np.sum(c * f, axis=1, keepdims=True) / np.sum(f, axis=1, keepdims=True), 0.25)
        score = score + wgt * c / mean
    chosen = np.argmax(np.where(feasible, score, -np.inf), axis=1)
    rows = np.arange(len(states))
    u = np.stack([V[rows, chosen], Wm[rows, chosen]], axis=1)
    return u, np.where(feasible[rows, chosen], chosen, -1)


# ---------------------------------------------------------------------------------------------


def scene(robots: int, seed: int = 0):
    import jaxplan as jp

    s = jp.WarehouseGenerator(96, 64, shelf_length=8, shelf_depth=2, aisle=3, cross_aisle=3, margin=2,
                              resolution=0.5)(0)
    grid = s.grid
    clear = jp.clearance_field(grid)
    ys, xs = np.nonzero(clear >= 0.5)
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, len(xs), robots)
    xy = (np.stack([xs[pick], ys[pick]], 1) + 0.5) * grid.resolution
    th = rng.uniform(-np.pi, np.pi, robots)
    states = np.column_stack([xy, th, rng.uniform(0, 1.2, robots), rng.uniform(-2, 2, robots)])
    goals = xy + rng.uniform(2, 6, (robots, 1)) * np.stack([np.cos(th + rng.normal(0, 0.7, robots)),
                                                            np.sin(th + rng.normal(0, 0.7, robots))], 1)
    return grid, states.astype(np.float32), goals.astype(np.float32)



# PythonRobotics' DWA scenario (PathPlanning/DynamicWindowApproach/dynamic_window_approach.py: `Config.ob`,
# `main`'s start state and goal). The numbers only; `pythonrobotics` checks them against the loaded file.
PR_OBSTACLES = np.array([[-1, -1], [0, 2], [4.0, 2.0], [5.0, 4.0], [5.0, 5.0], [5.0, 6.0], [5.0, 9.0], [8.0, 9.0],
                         [7.0, 9.0], [8.0, 10.0], [9.0, 11.0], [12.0, 13.0], [12.0, 12.0], [15.0, 15.0], [13.0, 13.0]])
PR_START = np.array([0.0, 0.0, np.pi / 8.0, 0.0, 0.0])
PR_GOAL = np.array([10.0, 10.0])
PR_FILE = "PathPlanning/DynamicWindowApproach/dynamic_window_approach.py"


def pythonrobotics():
    """PythonRobotics' DWA module loaded from ``PYTHONROBOTICS_DIR`` (a checkout or the file), or a message saying
    why not. matplotlib is imported by the module; a stand-in is used if it is not installed (nothing is drawn)."""
    import importlib.util
    import types
    from pathlib import Path

    root = os.environ.get("PYTHONROBOTICS_DIR")
    if not root:
        return None, ("PythonRobotics: skipped (set PYTHONROBOTICS_DIR to a checkout of "
                      "https://github.com/AtsushiSakai/PythonRobotics; its code is not part of jaxplan)")
    path = Path(root)
    path = path / PR_FILE if path.is_dir() else path
    if not path.is_file():
        return None, f"PythonRobotics: skipped ({path} not found)"
    try:
        import matplotlib

        matplotlib.use("Agg")
    except ImportError:
        plt = types.ModuleType("matplotlib.pyplot")
        sys.modules.setdefault("matplotlib", types.ModuleType("matplotlib"))
        sys.modules.setdefault("matplotlib.pyplot", plt)
    spec = importlib.util.spec_from_file_location("pythonrobotics_dwa", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    if not np.array_equal(np.asarray(module.config.ob, float), PR_OBSTACLES):
        return module, "PythonRobotics: its obstacle list differs from the one this benchmark reproduces"
    return module, None


def pythonrobotics_scene(res: float = 0.25, margin: float = 5.0):
    """PythonRobotics' scenario in jaxplan's terms: each point obstacle a blocked ``res`` cell centred on it (the
    origin sits half a cell off the points' grid), ``margin`` metres of free map round them; start and goal."""
    import jaxplan as jp

    lo = PR_OBSTACLES.min(0) - margin - res / 2
    hi = PR_OBSTACLES.max(0) + margin + res / 2
    W, H = np.round((hi - lo) / res).astype(int)
    free = np.ones((H, W), bool)
    cells = np.floor((PR_OBSTACLES - lo) / res).astype(int)
    free[cells[:, 1], cells[:, 0]] = False
    return jp.grid_from_array(free, resolution=res, origin=tuple(lo)), PR_START, PR_GOAL


def measure_pythonrobotics(repeat: int) -> dict:
    """The single-robot rows on PythonRobotics' scenario (milliseconds per call, medians), PythonRobotics' own
    `dwa_control` among them when it can be loaded."""
    import jax

    from jaxplan.dwa import DWAConfig, advance, default_params, dwa_control, dwa_step, make_stepper
    from jaxplan.dwa._step import _control_only, table_of

    grid, x, goal = pythonrobotics_scene()
    cfg = DWAConfig()
    step = make_stepper(grid, cfg)
    out: dict = {"points": cfg.samples * cfg.steps, "grid": list(grid.shape), "resolution": float(grid.resolution)}
    n = max(50, repeat * 30)
    # The stepper's own path (its checks, its device arrays) with the program compiled as XLA does by default:
    # large loops split across the intra-op threads (the stepper's program skips that split, `jaxplan.core.xla`).
    split = jax.jit(_control_only)

    def split_step():
        st, sg = step._robot(x, goal)
        return np.asarray(split(step.table, step._lean, step._params, st, sg))

    calls = {"stepper_ms": lambda: step(x, goal), "split_ms": split_step,
             "lean_ms": lambda: dwa_step(x, goal, grid, config=cfg, full_info=False),
             "full_ms": lambda: dwa_step(x, goal, grid, config=cfg)}
    for fn in calls.values():
        fn()
    # Interleaved rounds: stepper and split see the same moments of the machine's load.
    rounds: dict = {name: [] for name in calls}
    for _ in range(5):
        for name, fn in calls.items():
            rounds[name].append(median_time(fn, max(10, n // 5)))
    for name, ts in rounds.items():
        out[name] = float(np.median(ts)) * 1e3
    steps = 50
    lean = DWAConfig(keep_rollouts=False)

    @jax.jit
    def episode(table, cfg, params, state, goal):
        def body(st, _):
            u, info = dwa_control(table, cfg, params, st, goal)
            return advance(st, u, cfg.period), info.recovery
        return jax.lax.scan(body, state, None, length=steps)

    local = grid.to_local(np.stack([x[:2], goal]))
    start = np.concatenate([local[0], x[2:]]).astype(np.float32)
    args = (table_of(grid), jax.device_put(lean), jax.device_put(default_params()), jax.device_put(start),
            jax.device_put(local[1].astype(np.float32)))
    jax.block_until_ready(episode(*args))
    out["episode_ms"] = median_time(lambda: jax.block_until_ready(episode(*args)), max(15, 3 * repeat)) / steps * 1e3
    module, note = pythonrobotics()
    if note:
        out["note"] = note
    if module is not None and note is None:
        pr_cfg = module.config
        pr_cfg.robot_type = module.RobotType.circle
        ob = np.asarray(pr_cfg.ob)
        dw = module.calc_dynamic_window(PR_START.copy(), pr_cfg)
        n_v = len(np.arange(dw[0], dw[1], pr_cfg.v_resolution))
        n_w = len(np.arange(dw[2], dw[3], pr_cfg.yaw_rate_resolution))
        T = len(module.predict_trajectory(PR_START.copy(), 0.0, 0.0, pr_cfg))
        module.dwa_control(PR_START.copy(), pr_cfg, PR_GOAL, ob)
        out["pr_ms"] = median_time(lambda: module.dwa_control(PR_START.copy(), pr_cfg, PR_GOAL, ob),
                                   max(3, repeat // 2)) * 1e3
        out["pr_points"] = n_v * n_w * T
    return out


def measure(robots: list[int], repeat: int, sharded: bool) -> dict:
    import jax

    from jaxplan.dwa import DWAConfig, default_params, dwa_control, dwa_control_batch, dwa_step
    from jaxplan.dwa._clearance import PAD
    from jaxplan.dwa._step import table_of

    out: dict = {"devices": str(jax.devices()), "rows": []}
    for mode in ("hybrid", "bilinear"):
        cfg = DWAConfig(keep_rollouts=False, clearance=mode)
        params = jax.device_put(default_params())
        cfg_dev = jax.device_put(cfg)
        for B in robots:
            grid, states, goals = scene(B)
            table = table_of(grid)
            if B == 1:
                fn = jax.jit(dwa_control)
                args = (table, cfg_dev, params, jax.device_put(states[0]), jax.device_put(goals[0]))
            elif sharded:
                from jax.sharding import Mesh, NamedSharding
                from jax.sharding import PartitionSpec as P

                mesh = Mesh(np.array(jax.devices()), ("robots",))
                spec = NamedSharding(mesh, P("robots"))

                def run(t, c, p, s, g, mesh=mesh):
                    return jax.shard_map(lambda s, g: dwa_control_batch(t, c, p, s, g, chunk=None), mesh=mesh,
                                         in_specs=(P("robots"), P("robots")), out_specs=P("robots"))(s, g)

                fn = jax.jit(run)
                args = (table, cfg_dev, params, jax.device_put(states, spec), jax.device_put(goals, spec))
            else:
                fn = jax.jit(dwa_control_batch, static_argnames="chunk")
                args = (table, cfg_dev, params, jax.device_put(states), jax.device_put(goals))
            n = repeat if B < 1024 else max(3, repeat // 2)
            # The default processes a big batch in chunks of 128 robots; one vmap over all of them
            # compiles faster and runs slower (measured on its own row).
            whole = [False, True] if B > 128 and not sharded and mode == "hybrid" else [False]
            for one_vmap in whole:
                kw = dict(chunk=None) if one_vmap else {}
                t0 = time.perf_counter()
                compiled = fn.lower(*args, **kw).compile()
                compile_s = time.perf_counter() - t0
                call = blocking(compiled, args)
                call()
                jax_s = median_time(call, n)
                if one_vmap:
                    out["rows"].append(dict(mode="hybrid, one vmap", robots=B, jax_ms=jax_s * 1e3,
                                            points_per_s=B * cfg.samples * cfg.steps / jax_s, compile_s=compile_s))
                    continue
                u, info = compiled(*args)
                row = dict(mode=mode, robots=B, jax_ms=jax_s * 1e3, points_per_s=B * cfg.samples * cfg.steps / jax_s,
                           compile_s=compile_s)
            if mode == "hybrid":
                quads = np.asarray(table.quads)
                nst = functools.partial(numpy_step, quads, float(grid.resolution), grid.shape, states, goals, cfg, PAD)
                nu, nchosen = nst()
                row["numpy_ms"] = median_time(nst, max(1, min(n, 5 if B < 1024 else 1))) * 1e3
                chosen = np.asarray(info.chosen).reshape(-1)
                row["same_choice"] = float(np.mean(chosen == nchosen))
                ok = nchosen >= 0  # recovery controls are not part of the numpy version
                row["max_control_diff"] = float(np.max(np.abs(np.asarray(u).reshape(-1, 2)[ok] - nu[ok]), initial=0.0))
            out["rows"].insert(len(out["rows"]) - (len(whole) - 1), row)  # the default row first
    grid, states, goals = scene(1)
    dwa_step(states[0], goals[0], grid)
    out["front_ms"] = median_time(lambda: dwa_step(states[0], goals[0], grid), repeat * 5) * 1e3
    # Closed loop inside one compiled program, as a navigation episode runs it: per-step cost
    # without the per-call dispatch (argument handling, output buffers, thread wake-ups).
    from jaxplan.dwa import advance

    cfg = DWAConfig(keep_rollouts=False)
    table = table_of(grid)
    steps = 50

    @jax.jit
    def episode(table, cfg, params, state, goal):
        def step(st, _):
            u, info = dwa_control(table, cfg, params, st, goal)
            return advance(st, u, cfg.period), info.recovery
        return jax.lax.scan(step, state, None, length=steps)

    args = (table, jax.device_put(cfg), jax.device_put(default_params()), jax.device_put(states[0]),
            jax.device_put(goals[0]))
    jax.block_until_ready(episode(*args))
    out["episode_step_ms"] = median_time(lambda: jax.block_until_ready(episode(*args)), repeat) / steps * 1e3
    out["lean_front_ms"] = median_time(lambda: dwa_step(states[0], goals[0], grid, full_info=False), repeat * 5) * 1e3
    if not sharded:  # the sharded child splits batches: its single-robot rows are not printed
        out["pythonrobotics"] = measure_pythonrobotics(repeat)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--robots", default="1,64,1024")
    ap.add_argument("--child", choices=["default", "pinned", "sharded"], help=argparse.SUPPRESS)
    args = ap.parse_args()
    robots = [int(b) for b in args.robots.split(",")]
    if args.child:
        print(json.dumps(measure(robots, args.repeat, args.child == "sharded")))
        return
    steal = Steal()
    record = Record("bench_dwa", {k: v for k, v in vars(args).items() if k != "child"})
    results = {}
    # The sharded child splits batches over two devices: nothing to run with one robot only.
    labels = ("default", "pinned", "sharded") if any(b > 1 for b in robots) else ("default", "pinned")
    for label in labels:
        env = dict(os.environ)
        pre = None
        if label == "pinned":
            pre = lambda: os.sched_setaffinity(0, {0})  # noqa: E731
        if label == "sharded":
            env["XLA_FLAGS"] = (env.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=2").strip()
        proc = subprocess.run([sys.executable, __file__, "--child", label, "--repeat", str(args.repeat),
                               "--robots", ",".join(str(b) for b in robots if label != "sharded" or b > 1)],
                              capture_output=True, text=True, preexec_fn=pre, env=env, check=True)
        results[label] = json.loads(proc.stdout.strip().splitlines()[-1])
    print(f"machine: {machine_line()}; 20 x 40 samples, 20 steps of 0.1 s (16,000 trajectory points per robot)")
    names = {"default": "XLA default threads", "pinned": "pinned to 1 core", "sharded": "batch over 2 host devices"}
    print(f"\n{'threads':<26}{'clearance':<17}{'robots':>7} | {'ms/step':>9}{'M pts/s':>9}{'compile s':>10} | "
          f"{'numpy ms':>10}{'x numpy':>8}{'same choice':>12}")
    steps = record.table("control step", ["threads", "clearance", "robots", "ms/step", "M points/s", "compile (s)",
                                          "numpy (ms)", "× numpy", "same choice (%)"],
                         "one compiled control step (20 × 40 samples × 20 steps of 0.1 s), median of "
                         f"{args.repeat}, beside the same step in vectorised numpy")
    for label, res in results.items():
        for r in res["rows"]:
            np_part = (f"{r['numpy_ms']:>10.2f}{r['numpy_ms'] / r['jax_ms']:>8.1f}{r['same_choice']:>12.1%}"
                       if "numpy_ms" in r else "")
            print(f"{names[label]:<26}{r['mode']:<17}{r['robots']:>7} | {r['jax_ms']:>9.3f}"
                  f"{r['points_per_s'] / 1e6:>9.1f}{r['compile_s']:>10.2f} | {np_part}")
            numpy = [r["numpy_ms"], r["numpy_ms"] / r["jax_ms"], 100 * r["same_choice"]] if "numpy_ms" in r else [
                None, None, None]
            steps.append([names[label], r["mode"], r["robots"], r["jax_ms"], r["points_per_s"] / 1e6, r["compile_s"],
                          *numpy])
    record.note("Targets: ≤ 0.2 ms per single-robot step, ≥ 200 M points/s for ≥ 64 robots, ≥ 3× numpy, compile "
                "≤ 1 s.")
    one = record.table("one robot", ["threads", "in a compiled episode (ms)", "dwa_step (ms)",
                                      "dwa_step(full_info=False) (ms)"],
                       "one robot's step inside a compiled 50-step episode, and from Python")
    for label in ("default", "pinned"):
        r = results[label]
        if "episode_step_ms" not in r:
            continue
        print(f"1 robot, {names[label]}: {r['episode_step_ms']:.3f} ms per control step inside a 50-step episode "
              f"(lax.scan, hybrid); host front dwa_step with every rollout kept: {r['front_ms']:.3f} ms, "
              f"full_info=False: {r['lean_front_ms']:.3f} ms")
        one.append([names[label], r["episode_step_ms"], r["front_ms"], r["lean_front_ms"]])
    pr_rows = record.table("PythonRobotics", ["threads", "make_stepper", "split", "full_info=False", "dwa_step",
                                              "in an episode", "stepper ÷ episode", "PythonRobotics dwa_control",
                                              "its points", "× PythonRobotics"],
                           "PythonRobotics' own DWA scenario, one robot, ms per call (jaxplan: 16,000 points per step)")
    print("\nPythonRobotics' DWA scenario, one robot, ms per call (jaxplan: 16,000 trajectory points per step):")
    print(f"{'threads':<26}{'stepper':>9}{'split':>8}{'lean':>8}{'dwa_step':>10}{'episode':>9}{'/episode':>10} | "
          f"{'PythonRobotics':>15}{'its points':>11}{'x PR':>7}")
    for label in ("default", "pinned"):
        r = results[label]["pythonrobotics"]
        pr = (f"{r['pr_ms']:>15.1f}{r['pr_points']:>11,}{r['pr_ms'] / r['stepper_ms']:>7.0f}" if "pr_ms" in r
              else f"{'—':>15}{'—':>11}{'—':>7}")
        print(f"{names[label]:<26}{r['stepper_ms']:>9.3f}{r['split_ms']:>8.3f}{r['lean_ms']:>8.3f}{r['full_ms']:>10.3f}"
              f"{r['episode_ms']:>9.3f}{r['stepper_ms'] / r['episode_ms']:>9.2f}x | {pr}")
        if "note" in r:
            print(f"  {r['note']}")
        pr_rows.append([names[label], r["stepper_ms"], r["split_ms"], r["lean_ms"], r["full_ms"], r["episode_ms"],
                        r["stepper_ms"] / r["episode_ms"], r.get("pr_ms"), r.get("pr_points"),
                        r["pr_ms"] / r["stepper_ms"] if "pr_ms" in r else None])
    record.note("split: the stepper's program as XLA compiles it by default (loops split across its threads). "
                "Targets: the Python-facing step ≤ 2× the in-episode step and ≥ 100× PythonRobotics "
                "(`PYTHONROBOTICS_DIR`: fetched, not vendored).")
    print("  stepper: make_stepper(grid)(state, subgoal); split: the same with the program as XLA compiles it by "
          "default (large loops split across its threads); lean: dwa_step(..., full_info=False); dwa_step: every "
          "rollout kept; episode: the step inside a compiled 50-step episode; x PR: PythonRobotics' dwa_control "
          "over the stepper")
    print("targets: <= 0.2 ms per single-robot step, >= 200 M points/s for >= 64 robots, >= 3x numpy, compile <= 1 s; "
          "Python-facing single-robot step <= 2x the in-episode step and >= 100x PythonRobotics")
    print(steal.summary())
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
