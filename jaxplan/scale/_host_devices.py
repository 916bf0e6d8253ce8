"""The library's CPU default: one XLA host device per core, and batches sharded over them.

Measured on the 2-core machine of DESIGN §7 (``python benchmarks/bench_scale.py``; in one
2-device process each call is timed with the mesh and with ``mesh=None`` in turn, medians of
5, so the machine's drift hits both alike): two host devices beat one by 1.20× for an `iaco`
`plan_batch` (16 scenarios × 2 seeds, 256 ants, 100×100 map; 1.07–1.15× in two runs of
``benchmarks/run_all.py --only scale``), 1.36× for `navigate_batch` (16
static `iaco_dwa` episodes) and 1.26× for one tuning generation (16 members); a 1-device
process with XLA's Eigen thread pool off (``--xla_cpu_multi_thread_eigen=false``) ran as
fast as with the default (1.00×).
XLA runs one host device's scan-heavy program mostly on one thread; two devices keep both
cores busy. A sharded ACO walk takes its device's share of the cores
(`jaxplan.aco._walk_numba.sharing_cores`; with two walk threads per device, three
between-process runs gave 0.96–1.25×). So, at ``import jaxplan``:

* the CPU backend gets one host device per core of this process's affinity
  (``jax.config.update("jax_num_cpu_devices", n)``) — unless ``$JAXPLAN_HOST_DEVICES``
  says otherwise (a count, or ``auto`` = cores, or ``off`` = leave JAX alone), the user
  already chose (``XLA_FLAGS=--xla_force_host_platform_device_count``,
  ``$JAX_NUM_CPU_DEVICES``, ``jax.config.update("jax_num_cpu_devices", n)`` before the
  import), or JAX's backend has already started (then nothing changes). "Cores" are the
  process's CPU affinity capped by a cgroup CPU quota;
* batched entry points (`jaxplan.plan_batch`, `Objective.evaluate` of `jaxplan.tune`,
  `jaxplan.navigate_batch` when its re-planning budget is per group of episodes) take
  ``mesh="auto"``: a batch that gives every local device at least `AUTO_MIN_PER_DEVICE`
  elements is split over them (`auto_mesh`); ``mesh=None`` keeps it on one device. Sharding changes no
  path, cost or episode (every batch element is computed on its own; tests compare 4
  devices with 1); float sums that XLA compiles per batch shape (a tuning objective's mean
  clearance) can differ in the last bit, as between batch sizes on one device.

Unbatched work (one `jaxplan.plan`, one DWA step) is not split: it runs on the first device as
before. On a GPU the CPU setting is irrelevant and ``"auto"`` shards over the local GPUs.
"""

from __future__ import annotations

import math
import os
from typing import Any

import jax
from jax.sharding import Mesh

from jaxplan.scale._mesh import batch_mesh, check_mesh

__all__ = ["HOST_DEVICES_ENV", "AUTO_MIN_PER_DEVICE", "host_devices_setting", "configure_host_devices", "auto_mesh"]

HOST_DEVICES_ENV = "JAXPLAN_HOST_DEVICES"


def _cores() -> int:
    """Cores this process may use: its CPU affinity, capped by a cgroup v2 CPU quota (a container's
    ``--cpus``), which the affinity does not show."""
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        n = os.cpu_count() or 1
    try:
        quota, period = open("/sys/fs/cgroup/cpu.max").read().split()[:2]
        if quota != "max":
            n = min(n, max(1, math.ceil(int(quota) / int(period))))
    except (OSError, ValueError):
        pass
    return n


def host_devices_setting(value: str | None = None) -> int | None:
    """The host device count asked for by ``value`` (default ``$JAXPLAN_HOST_DEVICES``).

    Unset, empty or ``auto`` → the cores of this process's affinity; ``off`` → None (leave
    JAX's default); a positive integer → that many.

    Raises:
      ValueError: anything else, naming the variable.
    """
    raw = os.environ.get(HOST_DEVICES_ENV, "") if value is None else value
    raw = raw.strip().lower()
    if raw in ("", "auto"):
        return _cores()
    if raw in ("off", "none", "jax"):
        return None
    try:
        n = int(raw)
    except ValueError:
        n = 0
    if n < 1:
        raise ValueError(f"${HOST_DEVICES_ENV} must be a positive integer, 'auto' or 'off', got {raw!r}")
    return n


def _user_chose() -> bool:
    return ("xla_force_host_platform_device_count" in os.environ.get("XLA_FLAGS", "")
            or bool(os.environ.get("JAX_NUM_CPU_DEVICES"))
            or jax.config.jax_num_cpu_devices != -1)  # set in-process before `import jaxplan`


def configure_host_devices() -> int | None:
    """Applies `host_devices_setting` to JAX's CPU backend if nobody chose and it has not started.

    Returns the count set, or None when it left JAX alone.
    """
    if _user_chose():
        return None
    n = host_devices_setting()
    if n is None:
        return None
    try:
        jax.config.update("jax_num_cpu_devices", n)
    except RuntimeError:  # the backend is already running: its device count is fixed
        return None
    return n


AUTO_MIN_PER_DEVICE = 8
"""``mesh="auto"`` splits a batch only if every device gets at least this many elements.

Measured (`benchmarks/run_all.py --only scale`, 2 devices against ``mesh=None`` timed in turn):
an `iaco` `plan_batch` of 8 scenarios (4 per device) ran at 0.87–1.03×, one of 16 (8 per
device) at 1.07–1.20×: with few scenarios per device, the device with the longer walks
keeps the other waiting, while one device's walk threads share all its ants."""


def auto_mesh(mesh: Any, batch: int) -> Mesh | None:
    """The mesh a batched entry point uses for a batch axis of ``batch`` elements.

    ``"auto"``: all local devices if there are several and each gets at least
    `AUTO_MIN_PER_DEVICE` elements, else None. None: None (one device). A `Mesh`: itself,
    checked (`check_mesh`).
    """
    if mesh is None:
        return None
    if isinstance(mesh, str):
        if mesh != "auto":
            raise ValueError(f"mesh must be a jax.sharding.Mesh, None or 'auto', got {mesh!r}")
        local = jax.local_devices()
        if len(local) < 2 or batch < AUTO_MIN_PER_DEVICE * len(local):
            return None
        return batch_mesh(local)
    return check_mesh(mesh)
