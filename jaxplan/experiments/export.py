"""A run folder's trials and per-trial arrays as long tables: `run_tables`, and `export_run` to npz or parquet
(``jaxplan export RUN --format npz|parquet``).

The arrays come from the run's checkpoints (`jaxplan.experiments.store.load_chunk_arrays`, each checked against
its SHA-256), labelled from the manifest (map, planner, kind, scenario range of each chunk) and ``meta.json``
(the seeds); no map is loaded and nothing is planned. Tables, one row per:

* ``trials``: trial — trials.csv as it is (one column per metric).
* ``paths``: path cell of a plan trial, or vertex of a navigation trial's global plan (``x``, ``y`` cells), or
  city of a TSP tour (``city``).
* ``histories``: iteration of a plan trial (``best_cost``, ``diversity``, ``successes``) or TSP trial
  (``best_cost``: best tour length so far).
* ``trajectories``: control step of a navigation trial (``t`` s, ``x``, ``y`` m, ``theta`` rad, ``v`` m/s,
  ``omega`` rad/s).

Every table but ``trials`` starts with ``map``, ``planner``, ``kind``, ``scenario`` (index in the map's scenario
list) and ``seed``. npz (always available) holds ``TABLE.COLUMN`` arrays, text as fixed-width unicode, so
``np.load(path)`` reads it without pickle; parquet (pyarrow: ``pip install 'jaxplan[export]'``) writes
``OUT/TABLE.parquet``. A table with no rows (e.g. no trajectories in a planning run) is left out.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from jaxplan.core.export import require_pandas
from jaxplan.core.io import atomic_file, atomic_path

__all__ = ["FORMATS", "run_tables", "trials_dataframe", "export_run"]

FORMATS = ("npz", "parquet")


def _seeds(run_dir: Path) -> list[int] | None:
    """The run's seeds from meta.json (ranges), or None if it is missing or damaged."""
    try:
        meta = json.loads((run_dir / "meta.json").read_text())
        return [s for lo, hi in meta["seeds"] for s in range(int(lo), int(hi))]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _labels(entry: dict, n: int, R: int, seeds: list[int] | None, extra: int = 1) -> dict[str, np.ndarray]:
    """Label columns of ``n × R × extra`` rows (scenario-major) of one chunk."""
    lo = int(entry.get("scenarios", [0, n])[0])
    sc, se = np.meshgrid(lo + np.arange(n), np.arange(R), indexing="ij")
    sc, se = np.repeat(sc.ravel(), extra), np.repeat(se.ravel(), extra)
    seed = np.asarray(seeds)[se] if seeds is not None and len(seeds) == R else se
    rows = len(sc)
    return {"map": np.full(rows, str(entry.get("map", "")), object),
            "planner": np.full(rows, str(entry.get("planner", "")), object),
            "kind": np.full(rows, str(entry.get("kind", "")), object), "scenario": sc, "seed": seed}


def _ragged(lab: dict, pts: np.ndarray, counts: np.ndarray) -> tuple[dict, np.ndarray, np.ndarray]:
    """Rows of ``pts [n, R, P, ...]`` kept where the step index < ``counts [n, R]``: (labels, step, values)."""
    n, R, P = pts.shape[:3]
    keep = (np.arange(P)[None, None, :] < counts[..., None]).reshape(-1)
    step = np.tile(np.arange(P), n * R)[keep]
    return {k: v[keep] for k, v in lab.items()}, step, pts.reshape(n * R * P, *pts.shape[3:])[keep]


def _chunk_tables(entry: dict, a: dict, seeds: list[int] | None) -> dict[str, dict[str, np.ndarray]]:
    """The path, history and trajectory rows of one chunk's arrays."""
    out: dict[str, dict[str, np.ndarray]] = {}
    if "tours" in a:  # tsp: [1, R, n] tours, [1, R, I] history
        t = np.asarray(a["tours"])
        n, R, C = t.shape
        lab, step, city = _ragged(_labels(entry, n, R, seeds, C), t[..., None], np.full((n, R), C))
        out["paths"] = {**lab, "step": step, "city": city[:, 0]}
    if "paths" in a or "plans" in a:
        pts = np.asarray(a["paths"] if "paths" in a else a["plans"])
        cnt = np.asarray(a["n_cells"] if "paths" in a else a["n_plan"])
        n, R, P = pts.shape[:3]
        lab, step, xy = _ragged(_labels(entry, n, R, seeds, P), pts, cnt)
        out["paths"] = {**lab, "step": step, "x": xy[:, 0], "y": xy[:, 1]}
    if "history" in a:
        h = np.asarray(a["history"])
        n, R, I = h.shape
        cols = {**_labels(entry, n, R, seeds, I), "iteration": np.tile(np.arange(1, I + 1), n * R),
                "best_cost": h.reshape(-1)}
        for k in ("diversity", "successes"):
            if k in a:
                cols[k] = np.asarray(a[k]).reshape(-1)
        out["histories"] = cols
    if "states" in a:
        st = np.asarray(a["states"])
        n, R, T = st.shape[:3]
        lab, step, s = _ragged(_labels(entry, n, R, seeds, T), st, np.asarray(a["steps"]) + 1)
        period = entry.get("period")
        cols = {**lab, "step": step}
        if period is not None:
            cols["t"] = step * float(period)
        out["trajectories"] = {**cols, "x": s[:, 0], "y": s[:, 1], "theta": s[:, 2], "v": s[:, 3], "omega": s[:, 4]}
    return out


def run_tables(run_dir: str | os.PathLike) -> dict[str, dict[str, np.ndarray]]:
    """Every table of the module docstring for a run folder, as columns (numpy arrays; text as ``object``).

    Raises:
      FileNotFoundError: not a run folder, or no finished chunk.
      CheckpointError: a chunk's arrays are missing, damaged or unreadable (naming the chunk).
    """
    from jaxplan.experiments.stats import read_trials
    from jaxplan.experiments.store import load_chunk_arrays, read_manifest

    run_dir = Path(run_dir)
    if not (run_dir / "config.toml").is_file():
        raise FileNotFoundError(f"{run_dir} is not a run folder (no config.toml); run `jaxplan run CONFIG` first")
    chunks = read_manifest(run_dir).get("chunks", {})
    if not chunks:
        raise FileNotFoundError(f"{run_dir} has no finished chunk yet")
    seeds = _seeds(run_dir)
    parts: dict[str, list[dict[str, np.ndarray]]] = {}
    for uid in sorted(chunks):
        entry = chunks[uid]
        if not entry.get("arrays"):
            continue
        arrays = load_chunk_arrays(run_dir, uid, entry.get("arrays_sha256"))
        for name, cols in _chunk_tables(entry, arrays, seeds).items():
            parts.setdefault(name, []).append(cols)
    tables: dict[str, dict[str, np.ndarray]] = {}
    trials = run_dir / "trials.csv"
    if trials.is_file():
        tables["trials"] = read_trials(trials)
    for name in ("paths", "histories", "trajectories"):
        got = parts.get(name, [])
        keys = [k for k in got[0]] if got else []
        for g in got[1:]:  # a run mixing kinds: columns of one kind missing in another become NaN
            keys += [k for k in g if k not in keys]
        if got:
            tables[name] = {k: np.concatenate([g[k] if k in g else np.full(len(g["scenario"]), np.nan)
                                               for g in got]) for k in keys}
    return tables


def trials_dataframe(run_dir: str | os.PathLike) -> Any:
    """A run's trials.csv as a `pandas.DataFrame` (pandas: ``pip install 'jaxplan[export]'``)."""
    from jaxplan.experiments.stats import read_trials

    pd = require_pandas("trials_dataframe()")
    return pd.DataFrame(read_trials(Path(run_dir) / "trials.csv"))


def _npz_column(v: np.ndarray) -> np.ndarray:
    return v.astype(str) if v.dtype == object else v


def export_run(run_dir: str | os.PathLike, out: str | os.PathLike | None = None, fmt: str = "npz") -> list[Path]:
    """Writes `run_tables` of ``run_dir`` as ``fmt``: ``npz`` → one file (default ``RUN/export.npz``),
    ``parquet`` → ``TABLE.parquet`` files in a folder (default ``RUN/export/``). Returns the files written.

    Raises:
      ValueError: an unknown format.
      ImportError: parquet without pyarrow (or pandas), saying what to install.
    """
    if fmt not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    run_dir = Path(run_dir)
    if fmt == "parquet":
        pd = require_pandas("--format parquet")
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise ImportError("--format parquet needs pyarrow, an optional extra of jaxplan: pip install "
                              "'jaxplan[export]' (or pip install pyarrow); --format npz needs nothing") from None
    tables = run_tables(run_dir)
    if fmt == "npz":
        path = Path(out) if out is not None else run_dir / "export.npz"
        path.parent.mkdir(parents=True, exist_ok=True)
        cols = {f"{t}.{c}": _npz_column(v) for t, tab in tables.items() for c, v in tab.items()}
        with atomic_file(path, "wb") as f:
            np.savez_compressed(f, **cols)
        return [path]
    folder = Path(out) if out is not None else run_dir / "export"
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, tab in tables.items():
        path = folder / f"{name}.parquet"
        with atomic_path(path) as tmp:
            pd.DataFrame(tab).to_parquet(tmp, index=False)
        written.append(path)
    return written
