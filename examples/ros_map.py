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
# # Planning on a ROS map with keep-out and speed masks
#
# Warehouse robots keep their maps as ROS `map_server` files (a PGM image and a YAML file), and Nav2 adds
# filter masks: **keep-out** zones a robot must not enter and **speed** zones where it must slow down. Here we
# load Nav2's warehouse with both masks, see how the keep-out zone reroutes an A* path, and drive a robot
# through a speed zone with the DWA and with MPPI, checking its speed against the limit.
#
# The map comes from `$JAXPLAN_DATA` or `../shared/benchmarks` (`ros/warehouse.yaml`, 1006 × 1674 cells at
# 0.03 m). Quick mode (`--quick` or `JAXPLAN_EXAMPLES_QUICK=1`) plans at 0.2 m per cell instead of 0.1 m; figures
# go to `$JAXPLAN_EXAMPLES_OUT` (default `runs/examples/`).

# %%
import json
import os
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import jaxplan as jp
from jaxplan.experiments import plots
from jaxplan.experiments.config import default_data_dir

QUICK = "--quick" in sys.argv or os.environ.get("JAXPLAN_EXAMPLES_QUICK", "") not in ("", "0")
OUT = Path(os.environ.get("JAXPLAN_EXAMPLES_OUT", "runs/examples"))
OUT.mkdir(parents=True, exist_ok=True)
ROS = default_data_dir() / "ros"  # $JAXPLAN_DATA, else ../shared/benchmarks beside the checkout

# %% [markdown]
# ## The map, with and without its masks
#
# `jp.load_map` reads a ROS YAML file; `keepout=` blocks the cells the keep-out mask marks, `speed=` adds
# `GridMap.speed_limit`, a fraction of the robot's top speed per cell. `resolution=` resamples the 0.03 m map
# (a coarse cell is blocked if any fine cell under it is), which planners need: a colony or a DWA at 3 cm per
# cell has a lot of cells to look at.

# %%
res = 0.2 if QUICK else 0.1
plain = jp.load_map(ROS / "warehouse.yaml", resolution=res)
masked = jp.load_map(ROS / "warehouse.yaml", resolution=res, keepout=ROS / "warehouse_keepout.yaml",
                     speed=ROS / "warehouse_speed.yaml")
keepout = np.asarray(plain.free) & ~np.asarray(masked.free)  # cells only the keep-out mask blocks
limits = np.asarray(masked.speed_limit)
print(f"{masked.shape[1]} x {masked.shape[0]} cells at {res} m, origin {masked.origin} m")
print(f"keep-out cells {int(keepout.sum())}, speed limits {sorted(set(np.round(limits, 2).ravel().tolist()))}")

# %% [markdown]
# ## The keep-out zone reroutes the plan
#
# Start and goal are given in world metres (the map frame of ROS) and turned into cells by `GridMap.cell_at`.
# The straight route from west to east crosses the keep-out square in the middle of the warehouse.

# %%
start, goal = masked.cell_at((-6.0, 0.5)), masked.cell_at((5.0, 0.5))
through = jp.plan(plain, start, goal, planner="astar")
around = jp.plan(masked, start, goal, planner="astar")
inside = keepout[through.path[:, 1], through.path[:, 0]].sum()
print(f"without the mask {through.length:.2f} m ({inside} cells in the keep-out zone); "
      f"with it {around.length:.2f} m, {keepout[around.path[:, 1], around.path[:, 0]].sum()} cells inside")

# %% [markdown]
# ## Driving through the speed zone
#
# Two-level navigation on the masked map: the A* plan reduced to key nodes, tracked by the DWA or by MPPI.
# Both cap the top speed at `v_max` times the limit of the cell the robot stands on; a robot entering a
# slower cell brakes at its full deceleration.

# %%
config = jp.NavConfig(max_time=60.0, replan=False)
if QUICK:
    config = config.replace(dwa=config.dwa.replace(n_v=10, n_omega=20), mppi=config.mppi.replace(samples=128))
v_max = float(config.dwa.robot.v_max)
episodes, drives = {}, {}
for local in ("dwa", "mppi"):
    ep = episodes[local] = jp.navigate(masked, start, goal, global_planner="astar", local_planner=local, seed=0,
                                       config=config)
    xy = np.asarray(ep.trajectory)[:-1, :2]
    cells = np.asarray(masked.cell_at(xy))
    cap = v_max * limits[cells[:, 1], cells[:, 0]]  # the limit where each control was chosen
    v = np.asarray(ep.controls)[:, 0]
    drives[local] = {"t": (np.arange(len(v)) * config.dwa.period).tolist(), "v": v.tolist(), "cap": cap.tolist()}
    over = v > cap + 1e-6
    print(f"{local:4s} {ep.reason}, {ep.time_s:.1f} s; {int(over.sum())} of {len(v)} controls above the limit where "
          f"chosen (allowed while braking into a zone); top speed in zones {v[cap < v_max].max(initial=0):.2f} m/s")

# %%
fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.4), constrained_layout=True,
                           gridspec_kw={"width_ratios": [1.1, 1]})
plots.plot_map(a, masked, keepout=keepout, y_up=True)
plots.plot_paths(a, masked, [through.path, around.path], labels=["A* without the mask", "A* with it"],
                 start=start, goal=goal)
for k, ep in enumerate(episodes.values()):
    a.plot(*np.asarray(ep.trajectory)[:, :2].T, lw=1.2, color=f"C{k + 2}", label=f"driven: {list(episodes)[k]}")
a.set_xlim(-9, 8)
a.set_ylim(-5, 6)
plots.legend_outside(a, ncol=3)
a.set_title("Nav2 warehouse: keep-out (hatched) and speed zones")
for k, (local, d) in enumerate(drives.items()):
    b.plot(d["t"], d["v"], color=f"C{k + 2}", label=f"{local} speed")
    b.plot(d["t"], d["cap"], color=f"C{k + 2}", ls=":", label=f"{local}: limit where it stands")
b.set_xlabel("time (s)")
b.set_ylabel("v (m/s)")
b.legend(fontsize=8)
b.set_title("speed against the speed mask's limit")
plots.save_figure(fig, str(OUT / "ros_map.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %%
(OUT / "ros_map.json").write_text(json.dumps({
    "length_without_mask": through.length, "length_with_mask": around.length,
    "keepout_cells_on_path": {"without": int(inside), "with": int(keepout[around.path[:, 1], around.path[:, 0]].sum())},
    "drives": drives}))
