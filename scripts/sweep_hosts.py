"""One host's part of a multi-host ACO sweep over a MovingAI scenario file, and the merge step.

Run the same command on every host (see `jaxplan.scale.initialize` for the variables), then merge:

    JAXPLAN_COORDINATOR=HOST0:9876 JAXPLAN_NUM_PROCESSES=2 JAXPLAN_PROCESS_ID=0 \\
        python scripts/sweep_hosts.py MAP SCEN --planner iaco --seeds 10 --out results/   # host 0
    JAXPLAN_COORDINATOR=HOST0:9876 JAXPLAN_NUM_PROCESSES=2 JAXPLAN_PROCESS_ID=1 \\
        python scripts/sweep_hosts.py MAP SCEN --planner iaco --seeds 10 --out results/   # host 1
    python scripts/sweep_hosts.py MAP SCEN --out results/ --merge 2                      # anywhere

Each host writes only ``results/sweep.host-K-of-N.npz``; the merge writes ``results/sweep.npz``.

The no-dependency way past one machine: every process must start and finish together (a dead one ends the sweep)
and the shares are fixed in advance. Where Ray can be installed, an experiment config run with
``jaxplan run CONFIG --ray HOST:PORT`` does the same work as retried, resumable tasks in a run folder
(docs/guide/scale-out.md).
"""

from __future__ import annotations

import argparse

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("map")
    ap.add_argument("scen")
    ap.add_argument("--planner", default="iaco")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--count", type=int, default=None, help="first COUNT scenario rows (default: all)")
    ap.add_argument("--ants", type=int, default=None)
    ap.add_argument("--iterations", type=int, default=None)
    ap.add_argument("--out", default="results")
    ap.add_argument("--name", default="sweep")
    ap.add_argument("--merge", type=int, metavar="N", help="merge the shards of N hosts instead of running")
    args = ap.parse_args()

    import jaxplan as jp
    from jaxplan.scale import batch_mesh, host_share, initialize, merge_shards, write_shard

    if args.merge:
        merged = merge_shards(args.out, args.name, args.merge)
        path = f"{args.out}/{args.name}.npz"
        np.savez(path, **merged)
        print(f"merged {args.merge} shards: {merged['length'].shape[0]} scenarios -> {path}")
        return
    jp.use_host_devices()  # as the CLI: one host device per core of this host, before JAX starts
    pid, n = initialize()
    import jax

    grid = jp.load_map(args.map)
    scen = jp.load_scenarios(args.scen, grid=grid)
    count = len(scen.starts) if args.count is None else min(args.count, len(scen.starts))
    share = host_share(count, pid, n)
    overrides = {k: v for k, v in (("ants", args.ants), ("iterations", args.iterations)) if v is not None}
    res = jp.plan_batch(grid, scen.starts[:count][share], scen.goals[:count][share], planner=args.planner,
                        seeds=range(args.seeds), mesh=batch_mesh(jax.local_devices()), **overrides)
    path = write_shard(args.out, args.name, {"length": res.length, "success": res.success, "cost": res.cost,
                                             "history": res.history, "optimal": scen.optimal[:count][share]},
                       pid, n)
    print(f"host {pid} of {n}: scenarios {share.start}..{share.stop - 1} on {len(jax.local_devices())} devices "
          f"in {res.time_s:.2f} s -> {path}")


if __name__ == "__main__":
    main()
