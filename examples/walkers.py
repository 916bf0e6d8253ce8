# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # A robot among walkers: DWA against MPPI
#
# A two-level planner: an exact A* path on the map inflated to the robot's safety distance, reduced to key
# nodes, tracked by a local planner that sees the walkers and predicts them at constant velocity. We drive
# the same robot with the Dynamic Window Approach (DWA) and with Model Predictive Path Integral control
# (MPPI) through the built-in 48 × 32 m warehouse among walkers on random routes, count successes and
# contacts over several walker draws, and animate one episode.
#
# No data needed. Quick mode (`--quick` or `JAXPLAN_EXAMPLES_QUICK=1`) uses fewer draws and smaller sample
# sets; figures go to `$JAXPLAN_EXAMPLES_OUT` (default `runs/examples/`).

# %%
import json
import os
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import jaxplan as jp
from jaxplan.experiments import plots
from jaxplan.experiments.pictures import animate_episodes, draw_episodes

QUICK = "--quick" in sys.argv or os.environ.get("JAXPLAN_EXAMPLES_QUICK", "") not in ("", "0")
OUT = Path(os.environ.get("JAXPLAN_EXAMPLES_OUT", "runs/examples"))
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## The scene and the settings
#
# `jp.NavConfig` holds the robot (a unicycle, 1.2 m/s, radius 0.25 m), the DWA's velocity window and the
# MPPI's samples. Quick mode samples fewer velocities and sequences and turns in-episode re-planning off:
# both mostly save compilation time.

# %%
scene = jp.demo_warehouse()
grid, start, goal = scene.grid, scene.start, scene.goal
base = jp.NavConfig(max_time=120.0)
if QUICK:
    config = base.replace(replan=False, dwa=base.dwa.replace(n_v=10, n_omega=20), mppi=base.mppi.replace(samples=128))
else:
    config = base
# walkers start 1.5 m clear of the robot's start and goal (a walker may not start inside the robot)
clear = grid.centre(np.stack([start, goal]))


def walkers(seed: int) -> jp.MovingObstacles:
    """Six blind walkers on random routes at 0.5 m/s: one draw per seed."""
    return jp.random_obstacles(grid, n=6, speed=0.5, radius=0.25, seed=seed, avoid=clear, avoid_radius=1.5)


# %% [markdown]
# ## One episode each
#
# `jp.navigate` plans and drives one episode. `global_planner="astar"` with `local_planner="dwa"` or `"mppi"`
# is the same system as the named pipelines `astar_kng_dwa` and `astar_kng_mppi` used below.

# %%
episodes = {}
for local in ("dwa", "mppi"):
    ep = episodes[local] = jp.navigate(grid, start, goal, global_planner="astar", local_planner=local, seed=0,
                                       obstacles=walkers(0), config=config)
    print(f"{local:4s} {ep.reason:10s} time {ep.time_s:5.1f} s, path {ep.metrics['path_length']:5.1f} m, "
          f"contacts {int(ep.collisions)} (active {int(ep.active_contacts)}, passive {int(ep.passive_contacts)})")

# %% [markdown]
# The executed trajectories over the global plan, with the walkers drawn at their closest approach to the
# robot (`jaxplan.experiments.pictures.draw_episodes`, the picture `jaxplan navigate --out x.png` draws):

# %%
fig, ax = plt.subplots(figsize=(8, 6.5), constrained_layout=True)
draw_episodes(ax, grid, episodes, title="seed 0: DWA and MPPI among six walkers")
plots.save_figure(fig, str(OUT / "walkers_episode.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %% [markdown]
# And as an animation (`animate_episodes`, the one behind `jaxplan demo` and `jaxplan navigate --out x.gif`;
# it needs Pillow, which matplotlib installs):

# %%
animate_episodes(episodes, grid, OUT / "walkers.gif", frames=15 if QUICK else 40)

# %% [markdown]
# ## Many walker draws
#
# `jp.navigate_batch` runs scenarios × seeds as one compiled episode program. `obstacles` may be a function
# of the scenario index and the seed: here each seed is one draw of walkers. A contact is **active** when the
# robot was moving (its fault, at least in part) and **passive** when a walker ran into it standing still.

# %%
draws = range(4 if QUICK else 24)
stats = {}
for local in ("dwa", "mppi"):
    batch = jp.navigate_batch(grid, np.asarray(start)[None], np.asarray(goal)[None], pipeline=f"astar_kng_{local}",
                              seeds=draws, obstacles=lambda i, seed: walkers(seed), config=config)
    stats[local] = {k: np.asarray(getattr(batch, k)).ravel().tolist()
                    for k in ("success", "collisions", "active_contacts", "passive_contacts")}
    stats[local]["time_s"] = [float(ep_time) for ep_time in np.asarray(batch.time_s).ravel()]
    s = batch.summary()
    print(f"{local:4s} success {s['success'][0]:4.0%}  time to goal {s['time_s'][0]:5.1f} s  "
          f"active contacts {s['active_contacts'][0]:.2f}  passive {s['passive_contacts'][0]:.2f} per episode")

# %%
fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.4), constrained_layout=True)
names = list(stats)
x = np.arange(len(names))
for k, (key, label) in enumerate((("success", "success rate"), ("active_contacts", "active contacts"),
                                  ("passive_contacts", "passive contacts"))):
    a.bar(x + (k - 1) * 0.27, [np.mean(stats[n][key]) for n in names], width=0.27, label=label)
a.set_xticks(x, [n.upper() for n in names])
a.set_ylabel("per episode")
a.set_title(f"{len(draws)} walker draws")
a.legend(fontsize=8)
arrivals = [[t for t, ok in zip(stats[n]["time_s"], stats[n]["success"], strict=True) if ok] for n in names]
b.boxplot(arrivals, showfliers=True)
b.set_xticks(x + 1, [n.upper() for n in names])
b.set_ylabel("time to goal (s), successful episodes")
b.set_title("arrival times")
plots.save_figure(fig, str(OUT / "walkers_stats.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %%
(OUT / "walkers.json").write_text(json.dumps(stats))
