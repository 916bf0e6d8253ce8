"""Planning on Nav2's warehouse (a ROS map_server map) at its own 0.03 m per cell and resampled to 0.1 m.

Run:  nice -n 10 python benchmarks/bench_ros_maps.py [--data-dir ../shared/benchmarks] [--seeds 1]
                                                     [--planners astar,iaco,iaco:heuristic=geodesic]
                                                     [--resolutions 0.03,0.1]

Loads ``ros/warehouse.yaml`` with its keep-out mask, picks start and goal by world coordinates (metres in the
map frame, as a ROS user gives them), and for each resolution and planner prints the path length (m), its gap
to the exact shortest path at that resolution, and the times: loading, resampling, the first call (compiles)
and a second, warm call. The load of the machine (1-minute load average) is printed first.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import jaxplan as jp

START_M = (-12.0, -22.0)  # world (map frame) metres
GOAL_M = (12.0, 21.0)


def _value(text: str):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data-dir", default=os.environ.get("JAXPLAN_DATA", "../shared/benchmarks"))
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--planners", default="astar,iaco,iaco:heuristic=geodesic",
                    help="comma-separated planners, each with optional :key=value overrides")
    ap.add_argument("--resolutions", default="0.03,0.1")
    a = ap.parse_args()
    ros = Path(a.data_dir) / "ros"
    print(f"load average (1 min): {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    t0 = time.perf_counter()
    fine = jp.load_map(ros / "warehouse.yaml", keepout=ros / "warehouse_keepout.yaml")
    print(f"loaded warehouse + keep-out: {fine.shape[1]}x{fine.shape[0]} cells at {fine.resolution} m, origin "
          f"{fine.origin}, {int((~fine.free).sum())} blocked, {time.perf_counter() - t0:.2f} s")
    print("| res (m) | cells | planner | seed | success | length (m) | gap to A* | first call (s) | warm call (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for res in (float(x) for x in a.resolutions.split(",")):
        t0 = time.perf_counter()
        grid = jp.resample(fine, res)
        rs = time.perf_counter() - t0
        s, g = grid.cell_at(START_M), grid.cell_at(GOAL_M)
        opt = None
        for spec in a.planners.split(","):
            planner, *sets = spec.split(":")
            kw = {k: _value(v) for k, v in (x.split("=", 1) for x in sets)}
            for seed in range(a.seeds):
                t0 = time.perf_counter()
                r = jp.plan(grid, s, g, planner=planner, seed=seed, **kw)
                first = time.perf_counter() - t0
                t0 = time.perf_counter()
                r = jp.plan(grid, s, g, planner=planner, seed=seed, **kw)
                warm = time.perf_counter() - t0
                if planner == "astar":
                    opt = r.length
                gap = f"{r.length / opt - 1:+.2%}" if (opt and r.success) else "-"
                print(f"| {res} | {grid.shape[1]}x{grid.shape[0]} (resampled in {rs:.2f} s) | {spec} | {seed} | "
                      f"{r.success} | {r.length:.2f} | {gap} | {first:.2f} | {warm:.2f} |", flush=True)
    print(f"start {START_M} m, goal {GOAL_M} m; load average (1 min) at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
