"""Device meshes for batched entry points, and the padding of uneven batches.

jaxplan shards only batch axes (scenarios of `plan_batch`, members of a tuning population):
every element of such a batch is computed independently of the others, so a batch split over
devices gives the same numbers as on one device, element for element. The work is spread by
JAX's SPMD machinery (`jax.shard_map` over a 1-D `jax.sharding.Mesh`), not by a scheduler of
ours; on a CPU, ``XLA_FLAGS=--xla_force_host_platform_device_count=N`` makes N host devices.
"""

from __future__ import annotations

from typing import Any, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh

__all__ = ["BATCH_AXIS", "batch_mesh", "check_mesh", "padded_size", "pad_leading"]

BATCH_AXIS = "batch"
"""The mesh axis name every batched entry point shards its batch over."""


def batch_mesh(devices: int | Sequence[jax.Device] | None = None) -> Mesh:
    """A 1-D mesh with axis `BATCH_AXIS` over ``devices``.

    Args:
      devices: None (every device of the default backend, across all hosts after
        `jax.distributed.initialize`), a count (the first that many), or a list of devices.
    """
    if devices is None:
        devs = jax.devices()
    elif isinstance(devices, (int, np.integer)):
        avail = jax.devices()
        if not 1 <= int(devices) <= len(avail):
            raise ValueError(f"devices must lie in [1, {len(avail)}] (the devices of this process), got {devices}")
        devs = avail[: int(devices)]
    else:
        devs = list(devices)
        if not devs:
            raise ValueError("devices must name at least one device")
    return Mesh(np.asarray(devs, dtype=object), (BATCH_AXIS,))


def check_mesh(mesh: Any) -> Mesh:
    """``mesh`` if it is a 1-D `Mesh` with axis `BATCH_AXIS`; a clear error otherwise."""
    if not isinstance(mesh, Mesh):
        raise ValueError(f"mesh must be a jax.sharding.Mesh (see jaxplan.scale.batch_mesh), got {type(mesh).__name__}")
    if tuple(mesh.axis_names) != (BATCH_AXIS,):
        raise ValueError(f"mesh must be 1-D with axis name {BATCH_AXIS!r}, got axes {tuple(mesh.axis_names)}")
    return mesh


def padded_size(n: int, mesh: Mesh) -> int:
    """The smallest multiple of the mesh's device count that holds ``n`` batch elements."""
    d = mesh.devices.size
    return -(-n // d) * d


def pad_leading(tree: Any, size: int) -> Any:
    """Pads every leaf's leading axis to ``size`` by repeating its last element.

    Repeats (not zeros) keep padded elements valid inputs: a padded scenario is a copy of a
    real one, so it cannot fail validation or produce NaNs; its results are sliced off.
    """

    def pad(a):
        n = a.shape[0]
        if n == size:
            return a
        if n == 0 or n > size:
            raise ValueError(f"cannot pad a batch of {n} to {size}")
        return jnp.concatenate([a, jnp.repeat(a[-1:], size - n, axis=0)], axis=0)

    return jax.tree_util.tree_map(pad, tree)
