"""The run folder's checkpoint store: finished chunks, the manifest that commits them, and ``meta.json``.

A finished chunk is committed in three steps: its rows are written to ``chunks/ID.csv``
(`jaxplan.core.io.atomic_write`: temporary file, fsync, `os.replace`), its arrays saved with
orbax, and only then is its entry added to ``manifest.json`` (again written atomically). The
manifest is the single commit point: a process killed at any instant (SIGKILL included) leaves
at worst a chunk that is not in the manifest, which the next run recomputes and overwrites.
Restarting with the same config skips every chunk in the manifest. The manifest holds the
experiment's `jaxplan.experiments.prepare.fingerprint`: a folder written by a different
experiment is refused (`RunFolderError`) rather than silently mixed. Each manifest entry records
the session (1 for the first invocation, 2 for the first restart, …) that computed it.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Sequence

import numpy as np

from jaxplan.core.io import TMP_GLOB, atomic_write
from jaxplan.experiments.config import ExperimentConfig
from jaxplan.experiments.prepare import Unit, sha256

__all__ = ["MANIFEST_VERSION", "RunFolderError", "Store", "read_manifest", "load_chunk_arrays", "write_meta"]

MANIFEST_VERSION = 1


class RunFolderError(ValueError):
    """The run folder holds a different experiment (or a damaged manifest)."""


def read_manifest(run_dir: str | os.PathLike) -> dict:
    """The manifest of a run folder: ``{"fingerprint", "sessions", "chunks": {uid: entry}}``."""
    p = Path(run_dir) / "checkpoints" / "manifest.json"
    return json.loads(p.read_text()) if p.is_file() else {"chunks": {}, "sessions": 0}


class Store:
    """The run folder's checkpoint store (see the module docstring); opening it starts a new session."""

    def __init__(self, run_dir: Path, fp: str):
        self.dir = run_dir
        self.ck = run_dir / "checkpoints"
        self.chunks = self.ck / "chunks"
        self.arrays = self.ck / "arrays"
        for d in (self.chunks, self.arrays):
            d.mkdir(parents=True, exist_ok=True)
        self.path = self.ck / "manifest.json"
        if self.path.is_file():
            try:
                self.manifest = json.loads(self.path.read_text())
            except json.JSONDecodeError as e:  # cannot happen with atomic writes; say so if it does
                raise RunFolderError(f"{self.path}: damaged manifest ({e}); delete the run folder") from None
            if self.manifest.get("fingerprint") != fp:
                raise RunFolderError(
                    f"{run_dir} holds the checkpoints of a different experiment (seeds, chunk size, maps, "
                    "scenarios, planners or metrics changed); delete that folder or pass another --out")
        else:
            self.manifest = {"version": MANIFEST_VERSION, "fingerprint": fp, "sessions": 0, "chunks": {}}
        # Leftovers of a killed writer: our temporary files and orbax's unfinished saves.
        for p in list(self.chunks.glob(TMP_GLOB)) + list(self.ck.glob(TMP_GLOB)):
            p.unlink(missing_ok=True)
        for p in self.arrays.glob("*.orbax-checkpoint-tmp*"):
            shutil.rmtree(p, ignore_errors=True)
        self.manifest["sessions"] += 1
        self.session = self.manifest["sessions"]
        self._save()

    def _save(self) -> None:
        atomic_write(self.path, json.dumps(self.manifest, indent=1, sort_keys=True).encode())

    def done(self, u: Unit) -> bool:
        e = self.manifest["chunks"].get(u.uid)
        f = self.chunks / f"{u.uid}.csv"
        return e is not None and f.is_file() and f.stat().st_size == e["bytes"]

    def commit(self, u: Unit, info: dict, text: str, arrays: dict, timing: dict) -> None:
        data = text.encode()
        atomic_write(self.chunks / f"{u.uid}.csv", data)
        arrays = {k: np.asarray(v) for k, v in arrays.items() if np.asarray(v).size}
        if arrays:
            import orbax.checkpoint as ocp

            ocp.PyTreeCheckpointer().save((self.arrays / u.uid).resolve(), arrays, force=True)
        self.manifest["chunks"][u.uid] = {**info, "bytes": len(data), "sha256": sha256(data), "session": self.session,
                                          "arrays": sorted(arrays), **timing}
        self._save()

    def merged(self, units: Sequence[Unit], header: str) -> bytes:
        return header.encode() + b"".join((self.chunks / f"{u.uid}.csv").read_bytes() for u in units)


def load_chunk_arrays(run_dir: str | os.PathLike, uid: str) -> dict[str, np.ndarray]:
    """The arrays (orbax) kept for chunk ``uid``: plan chunks ``history f32[n, R, I]``, ``diversity``,
    ``successes``, ``paths i32[n, R, P, 2]``, ``n_cells``, ``success``; navigate chunks ``positions
    f32[n, R, T, 2]`` (m), ``states f32[n, R, T, 5]`` (x, y, theta, v, omega), ``steps``, ``plans``, ``n_plan``,
    ``success``; tsp chunks ``history f32[1, R, I]`` (best tour length so far), ``tours i32[1, R, n]`` (the best
    tour, from city 0), ``success``. The manifest entry of ``uid`` names its map, planner and scenario range."""
    import orbax.checkpoint as ocp

    return ocp.PyTreeCheckpointer().restore((Path(run_dir) / "checkpoints" / "arrays" / uid).resolve())


def write_meta(run_dir: Path, cfg: ExperimentConfig, session: int, started: str) -> dict:
    """Writes ``meta.json``: the run's settings, its sessions and the provenance record (`jaxplan.core.provenance`).
    The flat version keys of earlier run folders stay, so readers of old and new folders read the same keys."""
    from jaxplan.core.provenance import provenance
    from jaxplan.core.version import VERSION

    p = run_dir / "meta.json"
    old = json.loads(p.read_text()) if p.is_file() else {}
    record = provenance()
    versions = record["versions"]
    rev = record["git_revision"]
    meta = {
        "experiment": cfg.name, "quick": cfg.is_quick, "chunk": cfg.chunk, "seeds": list(cfg.seeds),
        "jaxplan_version": VERSION, "git_revision": rev and (rev + ("+dirty" if record["git_dirty"] else "")),
        "jax_version": versions["jax"], "numpy_version": versions["numpy"], "scipy_version": versions["scipy"],
        "python": record["python"], "platform": record["platform"], "devices": record["devices"],
        "started": old.get("started", started),
        "sessions": old.get("sessions", []) + [{"session": session, "started": started}],
        "config_sha256": sha256(cfg.text.encode()), "provenance": record,
    }
    atomic_write(p, json.dumps(meta, indent=1).encode())
    return meta
