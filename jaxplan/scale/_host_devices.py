"""The explicit opt-in to one XLA host device per core, and the `mesh="auto"` rule of the batched entry points.

XLA runs one host device's scan-heavy program mostly on one thread, so on a CPU with several
cores several host devices, with batches sharded over them, keep every core busy (the speed-ups
and the measurements behind the rules below: docs/decisions.md). JAX decides its CPU device count
once, when its backend starts, and the setting is process-wide: it is the user's to choose. So
importing jaxplan changes no JAX setting; programs that want the devices opt in, before their
first JAX computation (docs/guide/navigation.md)::

    import jaxplan as jp
    jp.use_host_devices()          # one CPU host device per core (or jp.use_host_devices(4))
    batch = jp.plan_batch(grid, starts, goals, planner="iaco", seeds=range(8))   # mesh="auto": sharded

The command line (`jaxplan ...`) and the benchmarks call `use_host_devices()`. With no count it
defers to a choice made elsewhere: ``XLA_FLAGS=--xla_force_host_platform_device_count=N``,
``$JAX_NUM_CPU_DEVICES`` or ``jax.config.update("jax_num_cpu_devices", n)`` are left as they are,
and ``$JAXPLAN_HOST_DEVICES`` (a count, ``auto`` = cores, or ``off`` = leave JAX alone) overrides
the one-per-core default — the variable only acts through this opt-in, never at import. "Cores"
are the process's CPU affinity capped by a cgroup CPU quota.

Batched entry points (`jaxplan.plan_batch`, `Objective.evaluate` of `jaxplan.tune`,
`jaxplan.navigate_batch` when its re-planning budget is per group of episodes) take
``mesh="auto"``: a batch that gives every local device at least `AUTO_MIN_PER_DEVICE` elements is
split over them (`auto_mesh`); with one device (no opt-in) nothing is split; ``mesh=None`` keeps a
batch on one device. Sharding changes no path, cost or episode (every batch element is computed
on its own; tests compare 4 devices with 1); float sums that XLA compiles per batch shape (a
tuning objective's mean clearance) can differ in the last bit, as between batch sizes on one
device. A sharded ACO walk takes its device's share of the cores (`jaxplan.aco.sharing_cores`).

Unbatched work (one `jaxplan.plan`, one DWA step) is not split: it runs on the first device. On a
GPU the CPU setting is irrelevant and ``"auto"`` shards over the local GPUs.
"""

from __future__ import annotations

import math
import os
from typing import Any

import jax
from jax.sharding import Mesh

from jaxplan.scale._mesh import batch_mesh, check_mesh

__all__ = ["HOST_DEVICES_ENV", "MAX_HOST_DEVICES", "AUTO_MIN_PER_DEVICE", "host_devices_setting", "use_host_devices",
           "auto_mesh"]

HOST_DEVICES_ENV = "JAXPLAN_HOST_DEVICES"
MAX_HOST_DEVICES = 1024
"""The most host devices jaxplan asks XLA for: XLA starts them one by one when its backend starts, and a
count such as 100000 (a typo) hangs that start for hours; beyond the cores there is nothing to gain."""


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
    JAX's default); a positive integer up to `MAX_HOST_DEVICES` → that many.

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
    if n > MAX_HOST_DEVICES:
        raise ValueError(f"${HOST_DEVICES_ENV} = {raw} is more than the {MAX_HOST_DEVICES} host devices jaxplan "
                         f"starts (this machine has {_cores()} cores); unset it or use 'auto'")
    return n


def _chosen_elsewhere() -> int | None:
    """The CPU device count chosen outside jaxplan's default (``jax.config``, then the environment), or None;
    -1 when ``XLA_FLAGS`` forces a count (XLA reads it when the backend starts)."""
    chosen = jax.config.jax_num_cpu_devices  # type: ignore[attr-defined]  # an option, set at run time
    if chosen != -1:
        return int(chosen)
    env = os.environ.get("JAX_NUM_CPU_DEVICES", "").strip()
    if env:
        return int(env) if env.lstrip("-").isdigit() else -1
    return -1 if "xla_force_host_platform_device_count" in os.environ.get("XLA_FLAGS", "") else None


def use_host_devices(n: int | None = None) -> int | None:
    """Opts in to ``n`` JAX CPU host devices (default: one per core), so that ``mesh="auto"`` shards batches.

    Must run before JAX's backend starts (the first JAX computation, ``jax.devices()``, …): the count
    is fixed from then on. Calling it again with the count in effect is harmless.

    Args:
      n: the number of host devices, a positive integer. None: a choice made elsewhere stands
        (``jax.config``'s ``jax_num_cpu_devices``, ``$JAX_NUM_CPU_DEVICES``, ``XLA_FLAGS`` with
        ``--xla_force_host_platform_device_count``); else ``$JAXPLAN_HOST_DEVICES`` (a count, ``auto``,
        ``off``); else one device per core this process may use.

    Returns:
      The host device count set (or already in effect); None when JAX's own setting was left alone
      (chosen through the environment, or ``$JAXPLAN_HOST_DEVICES=off``).

    Raises:
      ValueError: ``n`` (or ``$JAXPLAN_HOST_DEVICES``) is not an integer in 1..`MAX_HOST_DEVICES`.
      RuntimeError: JAX's backend already runs with a different number of CPU devices.
    """
    if n is None:
        chosen = _chosen_elsewhere()
        if chosen is not None:
            return chosen if chosen > 0 else None
        n = host_devices_setting()
        if n is None:
            return None
    elif isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_HOST_DEVICES:
        raise ValueError(f"use_host_devices: n must be a positive integer up to {MAX_HOST_DEVICES} or None, got {n!r}")
    try:
        jax.config.update("jax_num_cpu_devices", n)
    except RuntimeError:  # JAX refuses once its backend runs; fine if the count is already the one asked for
        running = len(jax.devices("cpu"))
        if running != n:
            raise RuntimeError(
                f"jaxplan.use_host_devices({n}) came too late: JAX's backend already runs with {running} CPU "
                f"device(s), fixed when it started. Call it right after `import jaxplan`, before any JAX "
                f"computation (or set XLA_FLAGS=--xla_force_host_platform_device_count={n} before Python starts)."
            ) from None
    return n


AUTO_MIN_PER_DEVICE = 8
"""``mesh="auto"`` splits a batch only if every device gets at least this many elements: with few
scenarios per device, the device with the longer walks keeps the other waiting, while one device's
walk threads share all its ants (measurements: docs/decisions.md)."""


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
