"""The experiment's run folder: its chunks as the entries of a `jaxplan.core.run_folder.RunFolder`, and ``meta.json``.

A finished chunk is an entry of the run folder (`RUN_LAYOUT`): its rows in ``checkpoints/chunks/ID.csv``, its
arrays (orbax) in ``checkpoints/arrays/ID/``, its record in ``checkpoints/chunks/ID.json``, committed by the
manifest ``checkpoints/manifest.json`` — the single commit point, so a process killed at any instant (SIGKILL
included) leaves at worst a chunk that is not in the manifest, which the next run recomputes and overwrites.
Restarting with the same config skips every chunk in the manifest. The manifest holds the experiment's
`jaxplan.experiments.prepare.fingerprint`: a folder written by a different experiment is refused
(`RunFolderError`) rather than silently mixed. Each manifest entry records the session (1 for the first
invocation, 2 for the first restart, …) that computed it.

Integrity (`jaxplan.core.run_folder`). Each entry holds the SHA-256 of the chunk's rows and of its array files. On
resume every committed chunk is checked against them (a file edited to the same size included), and once more as
the rows are merged into ``trials.csv``; a chunk that fails, or whose arrays are missing, is recomputed — never
merged. A manifest that is damaged, emptied or deleted is rebuilt from the chunks' own records (the fingerprint and
the entry), keeping every chunk whose rows and arrays still match; the folder's ``notes`` say what was done, for
the progress output.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Sequence

import numpy as np

from jaxplan.core.io import atomic_write
from jaxplan.core.run_folder import (
    MANIFEST,
    MANIFEST_VERSION,
    CheckpointError,
    Layout,
    RunFolderError,
    arrays_digest,
    load_arrays,
    load_manifest,
    rebuilt_manifest,
)
from jaxplan.experiments.config import ExperimentConfig
from jaxplan.experiments.prepare import sha256

__all__ = ["MANIFEST_VERSION", "RUN_LAYOUT", "RunFolderError", "CheckpointError", "read_manifest",
           "load_chunk_arrays", "arrays_digest", "seed_ranges", "write_meta"]

RUN_LAYOUT = Layout(table="chunks", suffix=".csv", arrays="arrays", noun="chunk",
                    refusal="a different experiment (seeds, chunk size, maps, scenarios, planners or metrics changed); "
                            "delete that folder or pass another --out")
"""Where an experiment's run folder keeps its chunks (`jaxplan.core.run_folder.Layout`)."""


def read_manifest(run_dir: str | os.PathLike, fingerprint: str | None = None) -> dict:
    """The manifest of a run folder: ``{"fingerprint", "sessions", "chunks": {uid: entry}}``.

    A damaged or missing manifest is rebuilt in memory from the chunks' records when the experiment's
    ``fingerprint`` is given (`jaxplan.experiments.prepare.fingerprint`); without it a missing one is empty.

    Raises:
      RunFolderError: the manifest is damaged and no fingerprint was given to rebuild it, or it is newer than this
        jaxplan reads.
    """
    run_dir = Path(run_dir)
    path = run_dir / MANIFEST
    doc, problem = load_manifest(path, RUN_LAYOUT.table)
    if doc is not None:
        return doc
    if fingerprint is not None:
        return rebuilt_manifest(run_dir, fingerprint, RUN_LAYOUT)
    if problem is not None:
        raise RunFolderError(f"{path} is damaged ({problem}); run `jaxplan run CONFIG` with the run's config again: "
                             f"it rebuilds the manifest from the intact chunks")
    return {"chunks": {}, "sessions": 0}


def load_chunk_arrays(run_dir: str | os.PathLike, uid: str, expected_sha256: str | None = None
                      ) -> dict[str, np.ndarray]:
    """The arrays (orbax) kept for chunk ``uid``: plan chunks ``history f32[n, R, I]``, ``diversity``,
    ``successes``, ``paths i32[n, R, P, 2]``, ``n_cells``, ``success``; navigate chunks ``positions
    f32[n, R, T, 2]`` (m), ``states f32[n, R, T, 5]`` (x, y, theta, v, omega), ``steps``, ``plans``, ``n_plan``,
    ``success``; tsp chunks ``history f32[1, R, I]`` (best tour length so far), ``tours i32[1, R, n]`` (the best
    tour, from city 0), ``success``. The manifest entry of ``uid`` names its map, planner and scenario range.

    Args:
      expected_sha256: the entry's ``arrays_sha256``: the files are checked against it first.

    Raises:
      CheckpointError: the arrays are missing, fail their checksum or cannot be read (naming the folder).
    """
    folder = Path(run_dir) / "checkpoints" / RUN_LAYOUT.arrays / uid
    return load_arrays(folder, expected_sha256, f"the arrays of chunk {uid}")


def seed_ranges(seeds: Sequence[int]) -> list[list[int]]:
    """``seeds`` as half-open runs ``[[start, stop], ...]`` of consecutive integers: 30 seeds 0..29 are
    ``[[0, 30]]``, so ``meta.json`` stays small whatever the seed count."""
    out: list[list[int]] = []
    for s in seeds:
        s = int(s)
        if out and out[-1][1] == s:
            out[-1][1] = s + 1
        else:
            out.append([s, s + 1])
    return out


def write_meta(run_dir: Path, cfg: ExperimentConfig, session: int, started: str) -> dict:
    """Writes ``meta.json``: the run's settings, its sessions and the provenance record (`jaxplan.core.provenance`).
    The flat version keys of earlier run folders stay, so readers of old and new folders read the same keys;
    ``seeds`` is written as ranges (`seed_ranges`), ``seed_count`` beside it."""
    from jaxplan.core.provenance import provenance
    from jaxplan.core.version import VERSION

    p = run_dir / "meta.json"
    try:
        old = json.loads(p.read_text()) if p.is_file() else {}
    except (OSError, ValueError):  # a damaged meta.json is rewritten; the sessions before are then unknown
        old = {}
    old = old if isinstance(old, dict) else {}
    record = provenance()
    versions = record["versions"]
    rev = record["git_revision"]
    meta = {
        "experiment": cfg.name, "quick": cfg.is_quick, "chunk": cfg.chunk, "seeds": seed_ranges(cfg.seeds),
        "seed_count": len(cfg.seeds),
        "jaxplan_version": VERSION, "git_revision": rev and (rev + ("+dirty" if record["git_dirty"] else "")),
        "jax_version": versions["jax"], "numpy_version": versions["numpy"], "scipy_version": versions["scipy"],
        "python": record["python"], "platform": record["platform"], "devices": record["devices"],
        "started": old.get("started", started),
        "sessions": (old.get("sessions") if isinstance(old.get("sessions"), list) else [])
        + [{"session": session, "started": started}],
        "config_sha256": sha256(cfg.text.encode()), "provenance": record,
    }
    atomic_write(p, json.dumps(meta, indent=1).encode())
    return meta
