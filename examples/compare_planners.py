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
# # Compare planners on a MovingAI map
#
# A MovingAI scenario file lists start and goal cells together with the optimal path length (8-connected,
# no corner cutting, diagonal steps of √2). That is ground truth for free: each planner's **optimality
# gap**, `length / optimal − 1`, needs no extra search. Here exact A* and three ant colonies (Ant System,
# cui2025's IACO and yu2020's P-RACO) plan the same scenario rows of a warehouse map over several seeds,
# and we look at the distribution of their gaps.
#
# Run it as a script (`python examples/compare_planners.py --quick`) or open it as a notebook. Quick mode
# (`--quick` or `JAXPLAN_EXAMPLES_QUICK=1`) uses fewer scenarios, seeds and ants. Figures go to
# `$JAXPLAN_EXAMPLES_OUT` (default `runs/examples/`); the map comes from `$JAXPLAN_DATA` or
# `../shared/benchmarks`.

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
DATA = default_data_dir()  # $JAXPLAN_DATA, else ../shared/benchmarks beside the checkout

# %% [markdown]
# ## The map and the scenario rows
#
# `jp.load_scenarios` reads the `.scen` rows: `starts` and `goals` as `(x, y)` cells and `optimal` in cells
# (metres here: MovingAI maps load at 1 m per cell). Colonies walk at random early on, so we keep rows whose
# optimum is at most 80 m and take them evenly over that range.

# %%
grid = jp.load_map(DATA / "movingai/warehouse-10-20-10-2-1.map")
scen = jp.load_scenarios(DATA / "movingai/warehouse-10-20-10-2-1-random-1.scen")
rows = scen.select(scen.optimal <= 80.0)
rows = rows.select(np.linspace(0, len(rows.starts) - 1, 12 if QUICK else 40).round().astype(int))
seeds = range(3 if QUICK else 5)
print(f"map {grid.shape[1]}x{grid.shape[0]}, {len(rows.starts)} rows, optimum {rows.optimal.min():.1f}"
      f"-{rows.optimal.max():.1f} m, {len(seeds)} seeds")

# %% [markdown]
# ## Plan every row with every planner
#
# `jp.plan_batch` runs all rows × seeds of one planner as one compiled call and returns arrays with leading
# axes `[rows, seeds]`. Each planner takes only its own settings: A* has no colony.

# %%
colony = dict(ants=20, iterations=15) if QUICK else dict(ants=30, iterations=40)
planners = {
    "astar": {},
    "aco": colony,
    "iaco": colony,
    "praco": dict(colony, ants=colony["ants"] // 2),  # P-RACO runs several sub-colonies of this size
}
batches, gaps, success = {}, {}, {}
for name, settings in planners.items():
    batch = batches[name] = jp.plan_batch(grid, rows.starts, rows.goals, planner=name, seeds=seeds, **settings)
    gaps[name] = batch.length / rows.optimal[:, None] - 1.0  # [rows, seeds]; inf where a colony failed
    ok = success[name] = batch.success
    print(f"{name:6s} success {ok.mean():5.0%}  median gap {np.median(gaps[name][ok]):6.2%}  "
          f"worst {gaps[name][ok].max():6.2%}  {batch.time_s:.2f} s (+{batch.compile_s:.1f} s compile)")

# %% [markdown]
# A* is exact, so its gap is zero up to rounding: the check that our grid rules match MovingAI's. The colonies
# never beat the optimum on this 8-connected grid; how far above it they land is the question.

# %%
assert np.all(np.abs(gaps["astar"]) < 1e-6), "A* should match the .scen optimum"

# %% [markdown]
# ## The gap distribution per planner
#
# A box per planner over all successful (row, seed) runs, the runs themselves as dots, and the share of
# successful runs under each name.

# %%
fig, ax = plt.subplots(figsize=(6.5, 3.6), constrained_layout=True)
names = list(planners)
data = [100 * gaps[n][success[n]] for n in names]
ax.boxplot(data, showfliers=False, widths=0.5)
jitter = np.random.default_rng(0)
for k, d in enumerate(data, start=1):
    ax.plot(k + jitter.uniform(-0.15, 0.15, len(d)), d, ".", alpha=0.45, color="C0")
ax.set_xticks(range(1, len(names) + 1), [f"{n}\n{success[n].mean():.0%} success" for n in names])
ax.set_ylabel("optimality gap (%)")
ax.set_title(f"{len(rows.starts)} rows of warehouse-10-20-10-2-1 × {len(seeds)} seeds")
ax.grid(axis="y", alpha=0.3)
plots.save_figure(fig, str(OUT / "compare_planners_gaps.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %% [markdown]
# ## One row, every planner's path
#
# The row where Ant System's seed 0 strays farthest. `BatchResult.result(row, seed)` gives one run of a batch
# as a `PlanResult`.

# %%
i = int(np.argmax(np.where(success["aco"][:, 0], gaps["aco"][:, 0], -1.0)))
paths = {name: batch.result(i, 0).path for name, batch in batches.items()}
fig, ax = plt.subplots(figsize=(9, 4.2), constrained_layout=True)
plots.plot_map(ax, grid, title=f"row {i}: optimum {rows.optimal[i]:.1f} m")
plots.plot_paths(ax, grid, [paths.pop("astar")], labels=["astar (optimal)"], lw=5)  # wide: colonies may follow it
plots.plot_paths(ax, grid, list(paths.values()), labels=list(paths), start=rows.starts[i], goal=rows.goals[i])
plots.legend_outside(ax, ncol=4)
plots.save_figure(fig, str(OUT / "compare_planners_paths.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %% [markdown]
# The numbers behind the figures, for later analysis:

# %%
summary = {}
for name in planners:
    gap = np.where(success[name], gaps[name], np.nan).tolist()  # [rows][seeds]
    summary[name] = {"success": float(success[name].mean()), "time_s": batches[name].time_s,
                     "gap": [[None if np.isnan(g) else g for g in row] for row in gap]}  # None: no path found
(OUT / "compare_planners.json").write_text(json.dumps({"optimal": rows.optimal.tolist(), "planners": summary}))
