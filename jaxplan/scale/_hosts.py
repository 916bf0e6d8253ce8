"""Multi-host sweeps: `jax.distributed` wiring, each host's share of a batch, shard files and their merge.

A sweep over many hosts runs the same script on every host (one command per host)::

    # host k of n (k = 0 .. n-1); host 0's address is the coordinator
    JAXPLAN_COORDINATOR=10.0.0.1:9876 JAXPLAN_NUM_PROCESSES=n JAXPLAN_PROCESS_ID=k \\
        python scripts/sweep_hosts.py --map MAP --scen SCEN --out results/

`initialize` joins the hosts with `jax.distributed.initialize` (on clusters that JAX detects by
itself — SLURM, Open MPI, Cloud TPU — no variables are needed). Every host then takes its own
contiguous share of the scenarios (`host_share`), runs it with a mesh over its local devices
(`jax.local_devices()`: every GPU of the node, or the CPU's host devices), and writes only its own
shard (`write_shard`, atomic). `merge_shards` concatenates the shards in host order once all are
there; because every scenario's result depends only on that scenario and its seed, the merged
result equals a single-host run of the whole batch.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

import jax
import numpy as np

from jaxplan.core.io import atomic_file

__all__ = ["initialize", "host_share", "shard_path", "write_shard", "merge_shards"]


def initialize(coordinator_address: str | None = None, num_processes: int | None = None,
               process_id: int | None = None) -> tuple[int, int]:
    """Joins this process to a multi-host run; returns ``(process_id, num_processes)``.

    Arguments default to ``$JAXPLAN_COORDINATOR`` (``host:port`` of process 0),
    ``$JAXPLAN_NUM_PROCESSES`` and ``$JAXPLAN_PROCESS_ID``. With none of them set and
    ``num_processes`` unset, this is a single-host run and nothing is initialised.
    """
    env = os.environ
    coordinator_address = coordinator_address or env.get("JAXPLAN_COORDINATOR")
    if num_processes is None and env.get("JAXPLAN_NUM_PROCESSES"):
        num_processes = int(env["JAXPLAN_NUM_PROCESSES"])
    if process_id is None and env.get("JAXPLAN_PROCESS_ID"):
        process_id = int(env["JAXPLAN_PROCESS_ID"])
    if coordinator_address is None and num_processes is None:
        return 0, 1
    if num_processes is not None and num_processes < 1:
        raise ValueError(f"num_processes must be >= 1, got {num_processes}")
    if process_id is not None and num_processes is not None and not 0 <= process_id < num_processes:
        raise ValueError(f"process_id must lie in [0, {num_processes}), got {process_id}")
    jax.distributed.initialize(coordinator_address=coordinator_address, num_processes=num_processes,
                               process_id=process_id)
    return jax.process_index(), jax.process_count()


def host_share(n: int, process_id: int, num_processes: int) -> slice:
    """The contiguous slice of ``n`` batch elements that host ``process_id`` of ``num_processes`` takes.

    Shares differ in size by at most one; hosts past the end get an empty slice.
    """
    if not 0 <= process_id < num_processes:
        raise ValueError(f"process_id must lie in [0, {num_processes}), got {process_id}")
    base, extra = divmod(n, num_processes)
    start = process_id * base + min(process_id, extra)
    return slice(start, start + base + (process_id < extra))


def shard_path(out_dir: str | Path, name: str, process_id: int, num_processes: int) -> Path:
    """``OUT/NAME.host-K-of-N.npz``."""
    return Path(out_dir) / f"{name}.host-{process_id}-of-{num_processes}.npz"


def write_shard(out_dir: str | Path, name: str, arrays: Mapping[str, np.ndarray], process_id: int,
                num_processes: int) -> Path:
    """Writes this host's arrays (leading axis = its share) atomically: a killed host leaves no half file."""
    path = shard_path(out_dir, name, process_id, num_processes)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(path) as f:
        np.savez(f, **{k: np.asarray(v) for k, v in arrays.items()})  # type: ignore[arg-type]  # stub: allow_pickle
    return path


def merge_shards(out_dir: str | Path, name: str, num_processes: int) -> dict[str, np.ndarray]:
    """Concatenates the hosts' shards in host order; a missing shard or a mismatch is a clear error."""
    parts = []
    for k in range(num_processes):
        path = shard_path(out_dir, name, k, num_processes)
        if not path.exists():
            raise FileNotFoundError(f"shard of host {k} of {num_processes} is missing: {path}")
        with np.load(path) as z:
            parts.append({key: z[key] for key in z.files})
    keys = set(parts[0])
    for k, p in enumerate(parts):
        if set(p) != keys:
            raise ValueError(f"shard of host {k} holds {sorted(p)}, host 0's holds {sorted(keys)}")
    return {key: np.concatenate([p[key] for p in parts], axis=0) for key in sorted(keys)}
