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
# # The travelling salesman problem: ant colonies against the known optimum
#
# Ant colony optimisation began on the TSP, and yu2020's P-RACO (ranked sub-colonies that exchange pheromone
# on a ring) has a TSP mode. TSPLIB's eil51 (51 cities) comes with its optimal tour, so every run's gap to
# the optimum is exact. We compare Ant System, P-RACO and P-RACO with 2-opt local search over several seeds,
# their convergence, and the best tour beside the optimal one.
#
# The instance comes from `$JAXPLAN_DATA` or `../shared/benchmarks` (`tsplib/eil51.tsp`). Quick mode
# (`--quick` or `JAXPLAN_EXAMPLES_QUICK=1`) runs fewer seeds and iterations; figures go to
# `$JAXPLAN_EXAMPLES_OUT` (default `runs/examples/`).

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
TSPLIB = default_data_dir() / "tsplib"  # $JAXPLAN_DATA, else ../shared/benchmarks beside the checkout

# %% [markdown]
# ## The instance and its optimum
#
# `jp.load_tsplib` reads the cities and TSPLIB's rounded Euclidean distances; `jp.tour_length` measures any
# tour (here the published optimal one) with the same distances.

# %%
problem = jp.load_tsplib(TSPLIB / "eil51.tsp")
best_tour = jp.load_tour(TSPLIB / "eil51.opt.tour")
optimum = jp.tour_length(problem, best_tour)
print(f"{problem.name}: {problem.n} cities, optimal tour length {optimum:g}")

# %% [markdown]
# ## Solve with three colonies over several seeds
#
# `jp.solve_tsp` runs one colony for one seed as one compiled program; the same seed gives the same tour.
# P-RACO's `ants` is per sub-colony. `history` is the best length so far after each iteration.

# %%
iterations = 40 if QUICK else 300
seeds = range(3 if QUICK else 10)
solvers = {
    "Ant System": dict(planner="aco", ants=51),
    "P-RACO": dict(planner="praco", ants=17),
    "P-RACO + 2-opt": dict(planner="praco", ants=17, local_search="2opt"),
}
runs = {name: [jp.solve_tsp(problem, seed=s, iterations=iterations, **kw) for s in seeds]
        for name, kw in solvers.items()}
for name, rs in runs.items():
    gaps = np.array([r.length / optimum - 1 for r in rs])
    print(f"{name:15s} gap mean {gaps.mean():6.2%}  best {gaps.min():6.2%}  worst {gaps.max():6.2%}  "
          f"{np.mean([r.time_s for r in rs]):.2f} s per run")

# %% [markdown]
# ## Convergence, gaps and a tour

# %%
fig, (a, b, c) = plt.subplots(1, 3, figsize=(13, 3.8), constrained_layout=True)
for k, (name, rs) in enumerate(runs.items()):
    h = 100 * (np.stack([r.history for r in rs]) / optimum - 1)  # [seeds, iterations], % above the optimum
    it = np.arange(1, h.shape[1] + 1)
    a.plot(it, np.median(h, axis=0), color=f"C{k}", label=name)
    a.fill_between(it, h.min(axis=0), h.max(axis=0), color=f"C{k}", alpha=0.2)
    b.plot(np.full(len(rs), k) + np.linspace(-0.1, 0.1, len(rs)), h[:, -1], "o", color=f"C{k}")
a.set_xlabel("iteration")
a.set_ylabel("best so far, % above the optimum")
a.set_yscale("symlog", linthresh=1.0)
a.legend(fontsize=8)
a.set_title(f"median and range over {len(seeds)} seeds")
b.set_xticks(range(len(runs)), list(runs), fontsize=8)
b.set_ylabel("final gap (%)")
b.axhline(0, color="grey", lw=0.8)
b.set_title("final gap per seed")
name = "P-RACO"  # 2-opt finds the optimum itself on eil51, which would hide the differences
best = min(runs[name], key=lambda r: r.length)
xy = problem.coords
c.plot(*xy[np.append(best_tour, best_tour[0])].T, color="grey", lw=4, alpha=0.35, label=f"optimal ({optimum:g})")
c.plot(*xy[np.append(best.tour, best.tour[0])].T, "o-", ms=3, color="C3", label=f"{name} ({best.length:g})")
c.set_aspect("equal")
c.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.06), ncol=2)
c.set_title(f"best {name} tour beside the optimum")
plots.save_figure(fig, str(OUT / "tsp.png"))
fig  # noqa: B018 (a notebook shows the figure)

# %%
(OUT / "tsp.json").write_text(json.dumps({
    "optimum": optimum, "n": problem.n,
    "runs": {name: [{"seed": s, "length": r.length, "tour": r.tour.tolist()} for s, r in zip(seeds, rs, strict=True)]
             for name, rs in runs.items()}}))
