"""The one provenance record: which code, libraries and machine produced a result.

Run folders (``meta.json`` of `jaxplan.experiments`), tuning runs and the benchmarks (``benchmarks/run_all.py``'s
JSON and every script's machine line) describe their origin with `provenance`: the git revision and whether
the work tree had uncommitted changes, the CPU (model name, family/model/stepping and widest vector ISA:
two cloud VMs sold under the same model name can differ several-fold in speed, so the name alone does not
identify the machine), cores and this process's CPU affinity, memory, the host name, the versions of
Python, jaxplan, jax, jaxlib, numpy, scipy and numba, and JAX's devices.

Versions come from the installed distributions' metadata (`importlib.metadata`), so describing a process
imports none of those libraries; only ``devices=True`` imports JAX (and starts its backend). Imports nothing
from jaxplan (the bottom layer, `jaxplan.core`).
"""

from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path
from typing import Any

__all__ = ["GENERATED", "PACKAGES", "provenance", "git_revision", "cpu_info", "machine_line", "package_versions",
           "ram_gb", "usable_cores"]

PACKAGES = ("jaxplan", "jax", "jaxlib", "numpy", "scipy", "numba")
"""The distributions whose versions a record names."""

_ROOT = Path(__file__).resolve().parents[2]  # the checkout holding jaxplan/ (not a repository when installed)


GENERATED = ("docs/results", "figures", "benchmarks/results")
"""Tracked folders the project's own commands write (`jaxplan reproduce` rewrites pages and figures config by
config): a change there is an output of the commit, not a change to its sources, so it does not make it dirty."""


def git_revision(root: str | os.PathLike | None = None) -> tuple[str | None, bool | None]:
    """``(full commit hash, dirty)`` of the checkout at ``root`` (default: jaxplan's own); ``(None, None)`` when
    it is not a git work tree or git is missing. ``dirty``: tracked files other than the `GENERATED` outputs differ
    from the commit (so the second config of a reproduction, written after the first one's pages, still records
    the clean revision it ran)."""
    where = str(_ROOT if root is None else root)
    try:
        rev = subprocess.run(["git", "-C", where, "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=10).stdout.strip()
        if not rev:
            return None, None
        dirty = subprocess.run(["git", "-C", where, "status", "--porcelain", "--untracked-files=no", "--", ".",
                                *(f":(exclude){g}" for g in GENERATED)],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None, None
    return rev, bool(dirty)


def cpu_info() -> dict[str, Any]:
    """CPU model name, family/model/stepping, widest vector ISA and logical cores (Linux's /proc/cpuinfo;
    elsewhere the model name from `platform` and None/"unknown" for the rest)."""
    info: dict[str, Any] = {"model_name": platform.processor() or platform.machine(), "family": None,
                            "model": None, "stepping": None, "isa": "unknown", "cores": os.cpu_count()}
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return info
    fields: dict[str, str] = {}
    for line in text.splitlines():
        if not line.strip():
            break  # the first processor's block describes them all here
        key, _, value = line.partition(":")
        fields[key.strip()] = value.strip()
    info["model_name"] = fields.get("model name", info["model_name"])
    for key, name in (("cpu family", "family"), ("model", "model"), ("stepping", "stepping")):
        if fields.get(key, "").isdigit():
            info[name] = int(fields[key])
    flags = set(fields.get("flags", "").split())
    info["isa"] = ("AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "AVX" if "avx" in flags
                   else "no AVX" if flags else "unknown")
    return info


def usable_cores() -> int:
    """Cores of this process's CPU affinity (all logical cores where the platform has no affinity)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def machine_line(info: dict[str, Any] | None = None) -> str:
    """One line naming the CPU well enough to tell two VMs with the same model name apart."""
    c = cpu_info() if info is None else info
    gen = f" (family {c['family']}, model {c['model']})" if c["family"] is not None else ""
    return f"{c['model_name']}{gen}, {c['isa']}, {c['cores']} cores ({usable_cores()} usable)"


def ram_gb() -> float | None:
    """Total memory in GiB (Linux's /proc/meminfo), or None."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) / 2**20
    except (OSError, ValueError, IndexError):
        pass
    return None


def package_versions(names: tuple[str, ...] = PACKAGES) -> dict[str, str | None]:
    """Installed version of each distribution (None if not installed), without importing it."""
    from importlib.metadata import PackageNotFoundError, version

    out: dict[str, str | None] = {}
    for name in names:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def provenance(devices: bool = True, root: str | os.PathLike | None = None) -> dict[str, Any]:
    """The record of this process: code, libraries and machine (a JSON-able dict).

    Args:
      devices: list JAX's devices (imports JAX and starts its backend); False leaves ``devices`` None.
      root: the checkout whose git revision is recorded (default: jaxplan's own).

    Returns:
      ``{"git_revision": str | None, "git_dirty": bool | None, "cpu": str, "cpu_info": dict, "cpu_line": str,
      "cores": int, "affinity": list[int] | None, "ram_gb": float | None, "host": str, "python": str,
      "platform": str, "versions": {package: version | None}, "devices": list[str] | None,
      "xla_flags": str}``.
    """
    rev, dirty = git_revision(root)
    info = cpu_info()
    listed = None
    if devices:
        import jax

        listed = [str(d) for d in jax.devices()]
    return {
        "git_revision": rev, "git_dirty": dirty, "cpu": info["model_name"], "cpu_info": info,
        "cpu_line": machine_line(info), "cores": os.cpu_count(),
        "affinity": sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "ram_gb": ram_gb(), "host": platform.node(), "python": platform.python_version(),
        "platform": platform.platform(), "versions": package_versions(), "devices": listed,
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
    }
