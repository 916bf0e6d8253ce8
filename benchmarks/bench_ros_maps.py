"""Planning on Nav2's warehouse (a ROS map_server map) at its own 0.03 m per cell and resampled to 0.1 m.

Run:  nice -n 10 python benchmarks/bench_ros_maps.py [--data-dir ../shared/benchmarks] [--seeds 1]
                                                     [--planners astar,iaco,iaco:heuristic=geodesic]
                                                     [--resolutions 0.03,0.1]

Loads ``ros/warehouse.yaml`` with its keep-out mask, picks starts and goals by world coordinates (metres in the
map frame, as a ROS user gives them), and for each resolution and planner prints the path length (m), its gap
to the exact shortest path at that resolution, and the times: loading, resampling, the first call (compiles)
and a second, warm call; then episodes (DWA, MPPI) through a slow zone of the speed mask, with and without the
speed layer. The load of the machine (1-minute load average) is printed first and last. The tables also go to a
JSON record in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from _timing import Record

import jaxplan as jp

ROUTES = {  # start and goal in world (map frame) metres
    "aisle": ((-12.0, -22.0), (-12.0, -10.0)),  # along the west aisle, about 12 m
    "cross": ((-12.0, -22.0), (-12.0, 3.0)),  # up the aisle and past the shelf ends, about 25 m
    "across": ((-12.0, -22.0), (12.0, 21.0)),  # corner to corner around the shelves, about 57 m
}


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
    ap.add_argument("--speed", action=argparse.BooleanOptionalAction, default=True,
                    help="also run episodes through a slow zone of the speed mask (DWA and MPPI)")
    ap.add_argument("--routes", default="aisle,cross,across", help=f"comma-separated, of {', '.join(ROUTES)}")
    a = ap.parse_args()
    record = Record("bench_ros_maps", vars(a))
    table = record.table("plans", ["resolution (m)", "cells", "route", "planner", "seed", "success", "length (m)",
                                   "gap to A*", "first call (s)", "warm call (s)"],
                         "Nav2's warehouse with its keep-out mask, at its own 0.03 m and resampled")
    ros = Path(a.data_dir) / "ros"
    print(f"load average (1 min): {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    t0 = time.perf_counter()
    fine = jp.load_map(ros / "warehouse.yaml", keepout=ros / "warehouse_keepout.yaml")
    print(f"loaded warehouse + keep-out: {fine.shape[1]}x{fine.shape[0]} cells at {fine.resolution} m, origin "
          f"{fine.origin}, {int((~fine.free).sum())} blocked, {time.perf_counter() - t0:.2f} s")
    print("| res (m) | cells | route | planner | seed | success | length (m) | gap to A* | first call (s) "
          "| warm call (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for res in (float(x) for x in a.resolutions.split(",")):
        t0 = time.perf_counter()
        grid = jp.resample(fine, res)
        rs = time.perf_counter() - t0
        for route in a.routes.split(","):
            _route(a, grid, res, rs, route, table)
    record.note(f"Routes (start and goal in world metres): {ROUTES}.")
    if a.speed:
        speed_episodes(ros, record)
    print(f"routes {ROUTES}; load average (1 min) at the end: {os.getloadavg()[0]:.2f}")
    record.write()


def _route(a: argparse.Namespace, grid: jp.GridMap, res: float, rs: float, route: str, table: list[list]) -> None:
    s, g = grid.cell_at(ROUTES[route][0]), grid.cell_at(ROUTES[route][1])
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
            print(f"| {res} | {grid.shape[1]}x{grid.shape[0]} (resampled in {rs:.2f} s) | {route} | {spec} | "
                  f"{seed} | {r.success} | {r.length:.2f} | {gap} | {first:.2f} | {warm:.2f} |", flush=True)
            table.append([res, f"{grid.shape[1]}×{grid.shape[0]}", route, spec, seed, bool(r.success), r.length, gap,
                          first, warm])


ZONE_ROUTE = ((-14.0, 0.9), (-3.7, 0.9))  # west to east through the 80 % zone around the marker at (-7.5, 0)


def speed_episodes(ros: Path, record: Record, resolution: float = 0.1) -> None:
    """Episodes through a slow zone of Nav2's speed mask, with and without the speed layer: the robot's commanded
    speeds in the zone (its top speed times the mask's 80 %), and how many exceed the limit while it brakes."""
    grid = jp.load_map(ros / "warehouse.yaml", keepout=ros / "warehouse_keepout.yaml",
                       speed=ros / "warehouse_speed.yaml", resolution=resolution)
    print(f"\nspeed mask episodes at {resolution} m, {ZONE_ROUTE[0]} -> {ZONE_ROUTE[1]} m (world)")
    print("| local | speed layer | success | time (s) | steps in zone | max v in zone (m/s) | limit (m/s) "
          "| over the limit (braking) | speeds on entering | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    table = record.table("speed zone", ["local", "speed layer", "success", "time (s)", "steps in zone",
                                        "max v in zone (m/s)", "limit (m/s)", "over the limit (braking)",
                                        "speeds on entering", "wall (s)"],
                         f"episodes through the 80 % zone of Nav2's speed mask at {resolution} m")
    for local in ("dwa", "mppi"):
        for layer in (True, False):
            g = grid if layer else grid.replace(speed_limit=None)
            t0 = time.perf_counter()
            ep = jp.navigate(g, g.cell_at(ZONE_ROUTE[0]), g.cell_at(ZONE_ROUTE[1]), global_planner="astar",
                             local_planner=local, time_limit=60.0)
            wall = time.perf_counter() - t0
            cells = grid.cell_at(ep.trajectory[:-1, :2])  # where each control was chosen
            frac = grid.speed_limit[cells[:, 1], cells[:, 0]]
            v = ep.controls[:, 0]
            cfg = jp.NavConfig()
            vmax = float(cfg.dwa.robot.v_max if local == "dwa" else cfg.local_mppi().robot.v_max)
            zone = frac < 1
            limit = float(np.min(frac[zone])) * vmax if zone.any() else float("nan")
            over = zone & (v > limit + 1e-5)
            first = np.flatnonzero(zone)[:4]
            print(f"| {local} | {layer} | {ep.success} | {ep.time_s:.1f} | {int(zone.sum())} | "
                  f"{float(v[zone].max()) if zone.any() else float('nan'):.3f} | {limit:.3f} | {int(over.sum())} | "
                  f"{', '.join(f'{x:.2f}' for x in v[first])} | {wall:.1f} |", flush=True)
            table.append([local, layer, bool(ep.success), ep.time_s, int(zone.sum()),
                          float(v[zone].max()) if zone.any() else None, limit, int(over.sum()),
                          ", ".join(f"{x:.2f}" for x in v[first]), wall])


if __name__ == "__main__":
    main()
