"""ACO path quality against exact optima on MovingAI scenario rows: the shortest path, and each colony's own optimum.

Run:  python benchmarks/bench_aco_quality.py [--rows 20] [--seeds 10] [--data-dir ../shared/benchmarks]
                                             [--walk-backend auto|jax|numba] [--maps warehouse,random-32,...]
                                             [--only-defaults [--heuristic euclidean|geodesic|objective]]
                                             [--floor] [--planners aco,opt_ant]

For warehouse-10-20-10-2-1, random-32-32-20 and room-64-64-8, takes up to ``--rows``
scenario rows whose optimal length is at most 64 cells (spread evenly over the
file), runs every ACO planner with its default settings on all rows x seeds in one
batched call per map, and prints a table per planner: success (goal reached) and
the mean optimality gap of the raw grid path (length / optimal - 1). Variants that
are not length-optimising by design are also run with the geodesic heuristic
(jaxplan's documented improvement) for comparison. `opt_ant` runs in 8-direction
mode on the flat maps, and `risk_aco` without a risk layer, as the issue asks.

"own gap" is the gap to the planner's own optimum: the float64 cost of its path under its own
objective (`jaxplan.search.path_objectives`) over the exact minimum of that objective
(`jaxplan.search.exact_objective`: IACO's fitness, the risk cost uP + vH + wT, Opt Ant's
aL + bR (+ cH, 0 on these flat maps), P-RACO's ω1L + ω2N, the length for `aco`). Every colony
also runs at its defaults (the papers' settings, Euclidean heuristic), with the geodesic
heuristic and with the objective heuristic (η = 1 / (move cost + exact own cost-to-go),
`heuristic="objective"`), and `risk_aco` on a Poisson(1) risk layer (`jp.poisson_risk`, seed 0),
where its H term counts. ``--only-defaults`` runs just those rows; ``--floor`` only the objective
heuristic with β raised (14, 28) and with 200 iterations, to find where each colony's own gap stops falling.
The tables also go to a JSON record in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
from _timing import Record

import jaxplan as jp

MAPS = [
    ("warehouse-10-20-10-2-1.map", "warehouse-10-20-10-2-1-random-1.scen"),
    ("random-32-32-20.map", "random-32-32-20-random-1.scen"),
    ("room-64-64-8.map", "room-64-64-8-random-1.scen"),
]
MORE_MAPS = [  # the other shared maps, with --maps
    ("maze-32-32-2.map", "maze-32-32-2-random-1.scen"),
    ("random-64-64-20.map", "random-64-64-20-random-1.scen"),
    ("brc202d.map", "brc202d.map.scen"),
]
SETTINGS = [
    ("aco", {}),
    ("iaco", {}),
    ("risk_aco", {}),
    ("opt_ant", {"connectivity": 8, "vehicle_height": None}),
    ("praco", {}),
    ("iaco", {"heuristic": "geodesic"}),
    ("opt_ant", {"connectivity": 8, "vehicle_height": None, "heuristic": "geodesic", "b": 1.0}),
]
COLONY_NAMES = ("aco", "iaco", "risk_aco", "opt_ant", "praco")
DEFAULTS = [  # every colony at its defaults (the papers' settings), then with the geodesic and objective heuristics
    *((name, {}) for name in COLONY_NAMES),
    *((name, {"heuristic": "geodesic"}) for name in COLONY_NAMES),
    *((name, {"heuristic": "objective"}) for name in COLONY_NAMES),
    ("risk_aco", {"risk": "poisson"}),
    ("risk_aco", {"risk": "poisson", "heuristic": "geodesic"}),
    ("risk_aco", {"risk": "poisson", "heuristic": "objective"}),
]
FLOOR = [  # --floor: the objective heuristic with β raised and more iterations, where the 2 % target is missed
    *((name, {"heuristic": "objective", "beta": beta}) for name in COLONY_NAMES for beta in (14.0, 28.0)),
    *((name, {"heuristic": "objective", "beta": 28.0, "iterations": 200}) for name in COLONY_NAMES),
]


def own_gaps(grid, starts, goals, r, name: str, over: dict) -> np.ndarray:
    """``f64[N, R]`` each run's gap to its planner's own optimum (nan where the run failed)."""
    opt = jp.search.exact_objectives(grid, starts, goals, planner=name, **over)
    N, R, P = r.paths.shape[:3]
    ok = r.success.reshape(-1)
    cost = np.full(N * R, np.nan)
    cost[ok] = jp.search.path_objectives(r.paths.reshape(-1, P, 2)[ok], r.n_cells.reshape(-1)[ok], grid, name,
                                         **over)
    return cost.reshape(N, R) / opt[:, None] - 1


PAPER_CONFIGS = ("cui2025_table1", "chen2023_table4", "chu2024_tables3_5", "yu2020_tables2_3")


def paper_settings(root: Path, seeds: int, record: Record) -> None:
    """Each colony row of the papers' reproduction configs, on its own maps and scenarios, with its settings as
    they are: the gap to its own optimum. opt_ant with c > 0 on a height map has no exact optimum (H_msd is
    a variance): its row reports the gap to the exact minimum of a·L + b·R (c=0), an upper bound of the gap."""
    from jaxplan.aco import COLONIES
    from jaxplan.experiments import load_config, prepare
    from jaxplan.nav import get_pipeline
    from jaxplan.search import NonAdditiveCost

    print(f"\npaper settings (configs/*.toml as they are, {seeds} seeds):")
    print(f"{'config':<20}{'planner':<22}{'map':<14}{'runs':>5}{'success':>9}{'own gap':>9}{'own max':>9}  note")
    table = record.table("paper settings", ["config", "planner", "map", "runs", "success (%)", "own gap (%)",
                                            "own max (%)", "note"],
                         f"the colony rows of the reproduction configs as they are, {seeds} seeds")
    for name in PAPER_CONFIGS:
        prep = prepare(load_config(root / "configs" / f"{name}.toml"))
        for mw in prep.maps:
            for pc in prep.config.planners:
                planner = pc.global_planner if pc.kind == "navigate" else pc.name
                if pc.kind == "tsp" or planner not in COLONIES:
                    continue
                over = dict(get_pipeline(pc.name).planner_overrides) if pc.kind == "navigate" else {}
                over.update({k: tuple(v) if isinstance(v, list) else v for k, v in pc.overrides.items()})
                r = jp.plan_batch(mw.grid, mw.starts, mw.goals, planner=planner, seeds=range(seeds), **over)
                note = "" if pc.kind == "plan" else f"{pc.name}'s global planner, on the map as loaded (not inflated)"
                try:
                    own = own_gaps(mw.grid, mw.starts, mw.goals, r, planner, over)
                except NonAdditiveCost:  # the colony's full cost (with c·H) over min a·L + b·R <= its optimum
                    low = jp.search.exact_objectives(mw.grid, mw.starts, mw.goals, planner=planner,
                                                     **{**over, "c": 0.0})
                    own = np.where(r.success, r.cost / low[:, None] - 1, np.nan)
                    note = "H_msd on a height map: an upper bound (vs min a·L + b·R)"
                ok = r.success
                nan = float("nan")
                print(f"{name:<20}{pc.label[:21]:<22}{mw.spec.name[:13]:<14}{ok.size:>5}{ok.mean():>9.1%}"
                      f"{(np.nanmean(own[ok]) if ok.any() else nan):>9.2%}"
                      f"{(np.nanmax(own[ok]) if ok.any() else nan):>9.2%}  {note}", flush=True)
                table.append([name, pc.label, mw.spec.name, ok.size, 100 * ok.mean(),
                              100 * np.nanmean(own[ok]) if ok.any() else None,
                              100 * np.nanmax(own[ok]) if ok.any() else None, note])


def main() -> None:
    root = Path(__file__).resolve().parents[1]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-dir", default=os.environ.get("JAXPLAN_DATA", root.parent / "shared" / "benchmarks"))
    ap.add_argument("--rows", type=int, default=20)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--walk-backend", default="auto", choices=("auto", "jax", "numba"),
                    help="how the ants walk (identical results; see jaxplan.aco._walk_numba)")
    ap.add_argument("--maps", default=None,
                    help="comma-separated map name prefixes among all six shared maps (default: the first three)")
    ap.add_argument("--only-defaults", action="store_true", help="only the defaults / geodesic / risk-layer rows")
    ap.add_argument("--papers", action="store_true", help="only the paper configs' colony rows (--seeds seeds)")
    ap.add_argument("--floor", action="store_true", help="only the objective heuristic with β raised / more iterations")
    ap.add_argument("--planners", default=None, help="comma-separated colonies: only their rows")
    ap.add_argument("--heuristic", default=None, choices=("euclidean", "geodesic", "objective"),
                    help="with --only-defaults: only the rows with this heuristic")
    args = ap.parse_args()
    record = Record("bench_aco_quality", vars(args))
    if args.papers:
        paper_settings(root, args.seeds, record)
        record.write()
        return
    d = Path(args.data_dir) / "movingai"
    maps = MAPS if args.maps is None else [(m, sc) for m, sc in MAPS + MORE_MAPS
                                           if any(m.startswith(x) for x in args.maps.split(","))]
    settings = [] if args.only_defaults or args.floor else list(SETTINGS)
    settings += [x for x in (FLOOR if args.floor else DEFAULTS) if x not in settings]
    if args.planners is not None:
        settings = [(n, o) for n, o in settings if n in args.planners.split(",")]
    if args.heuristic is not None:
        settings = [(n, o) for n, o in settings if o.get("heuristic", "euclidean") == args.heuristic]
    print(f"{'planner':<10}{'overrides':<62}{'map':<26}{'runs':>6}{'success':>9}{'mean gap':>10}"
          f"{'max gap':>9}{'own gap':>9}{'own max':>9}{'run s':>8}{'compile s':>10}")
    # a run of a subset of the settings records tables of their own name, beside the full run's
    subset = ", ".join(x for x in ("only defaults" * args.only_defaults, "floor" * args.floor,
                                   args.planners and f"planners {args.planners}",
                                   args.heuristic and f"{args.heuristic} heuristic") if x)
    suffix = f" ({subset})" if subset else ""
    per_map = record.table(f"per map{suffix}", ["planner", "overrides", "map", "runs", "success (%)",
                                                "mean gap (%)", "max gap (%)", "own gap (%)", "own max (%)",
                                                "run (s)", "compile (s)"],
                           f"{args.rows} rows (optimal ≤ 64 cells) × {args.seeds} seeds per map; gap of the raw grid "
                           "path to the shortest, own gap to the colony's own optimum")
    totals: dict[str, list] = {}
    for m, sc in maps:
        grid = jp.load_map(d / m)
        scen = jp.load_scenarios(d / sc, grid=grid)
        short = np.nonzero(scen.optimal <= 64)[0]
        rows = short[np.linspace(0, len(short) - 1, min(args.rows, len(short))).astype(int)]
        risky = jp.poisson_risk(grid, 0)
        for name, over in settings:
            label = ", ".join(f"{k}={v}" for k, v in over.items()) or "defaults"
            over = dict(over)
            g = risky if over.pop("risk", None) == "poisson" else grid
            r = jp.plan_batch(g, scen.starts[rows], scen.goals[rows], planner=name, seeds=range(args.seeds),
                              walk_backend=args.walk_backend, **over)
            gap = r.length / scen.optimal[rows][:, None] - 1
            own = own_gaps(g, scen.starts[rows], scen.goals[rows], r, name, over)
            ok = r.success
            nan = float("nan")
            print(f"{name:<10}{label:<62}{m[:-4]:<26}{ok.size:>6}{ok.mean():>9.1%}"
                  f"{(gap[ok].mean() if ok.any() else nan):>10.2%}{(gap[ok].max() if ok.any() else nan):>9.2%}"
                  f"{(own[ok].mean() if ok.any() else nan):>9.2%}{(own[ok].max() if ok.any() else nan):>9.2%}"
                  f"{r.time_s:>8.1f}{r.compile_s:>10.1f}", flush=True)
            stats = [100 * float(f(x[ok])) if ok.any() else None for x in (gap, own) for f in (np.mean, np.max)]
            per_map.append([name, label, m[:-4], ok.size, 100 * ok.mean(), stats[0], stats[1], stats[2], stats[3],
                            r.time_s, r.compile_s])
            totals.setdefault(f"{name} ({label})", []).append((ok, gap, own))
    print("\nall maps:")
    pooled = record.table(f"all maps{suffix}", ["planner, setting", "success (%)", "mean gap (%)", "own gap (%)"],
                          f"pooled over {', '.join(m[:-4] for m, _ in maps)}")
    for key, parts in totals.items():
        ok = np.concatenate([p[0].ravel() for p in parts])
        gap = np.concatenate([p[1].ravel() for p in parts])
        own = np.concatenate([p[2].ravel() for p in parts])
        print(f"  {key:<70} success {ok.mean():7.1%}   mean gap {gap[ok].mean():7.2%}   own gap {own[ok].mean():7.2%}")
        pooled.append([key, 100 * ok.mean(), 100 * gap[ok].mean(), 100 * own[ok].mean()])
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
