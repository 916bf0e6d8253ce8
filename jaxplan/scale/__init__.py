"""Scale-out: device meshes for the batched entry points, memory estimates, multi-host runs.

``jp.plan_batch(..., mesh=jaxplan.scale.batch_mesh())`` splits the scenarios of an ACO batch over
every device (docs/guide/experiments.md); results equal the single-device call's. Before it allocates, `plan_batch`
estimates its working memory (`aco_memory`) and refuses a batch above `memory_limit()`
(``$JAXPLAN_MEMORY_LIMIT``, default 80 % of the available memory) with `MemoryLimitError`,
naming the largest batch that fits; `jaxplan.solve_tsp` (`tsp_memory`), a tuning population, an
experiment's chunks (navigation: `episode_memory`) and trials (`table_memory`) are guarded the same
way. Multi-host sweeps: `initialize` (`jax.distributed`), each host's `host_share` of the batch,
`write_shard` and `merge_shards` (recipe in ``scripts/sweep_hosts.py``). On a CPU,
`use_host_devices` (also ``jaxplan.use_host_devices``) is the explicit opt-in to one host device per
core, after which ``mesh="auto"`` shards large batches over them; importing jaxplan changes no JAX
setting (`jaxplan.scale._host_devices`).
"""

from jaxplan.scale._host_devices import (
    AUTO_MIN_PER_DEVICE,
    HOST_DEVICES_ENV,
    auto_mesh,
    host_devices_setting,
    use_host_devices,
)
from jaxplan.scale._hosts import host_share, initialize, merge_shards, shard_path, write_shard
from jaxplan.scale._memory import (
    Knob,
    MemoryEstimate,
    MemoryLimitError,
    aco_memory,
    check_memory,
    dwa_memory,
    episode_memory,
    largest_count,
    memory_limit,
    table_memory,
    tsp_memory,
)
from jaxplan.scale._mesh import BATCH_AXIS, batch_mesh, check_mesh, pad_leading, padded_size

__all__ = ["AUTO_MIN_PER_DEVICE", "HOST_DEVICES_ENV", "auto_mesh", "host_devices_setting", "use_host_devices",
           "BATCH_AXIS", "batch_mesh", "check_mesh", "pad_leading", "padded_size", "Knob", "largest_count",
           "MemoryEstimate",
           "MemoryLimitError", "aco_memory", "check_memory", "dwa_memory", "episode_memory", "table_memory",
           "tsp_memory", "memory_limit", "host_share", "initialize", "merge_shards", "shard_path", "write_shard"]
