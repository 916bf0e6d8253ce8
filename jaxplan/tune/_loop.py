"""`tune_loop`: one `Strategy` on one `Objective` for G generations, checkpointed in a run folder, resumed exactly.

Generation g draws its key as ``fold_in(key(seed), g)`` — a function of (seed, g) only — so a run that is killed
and resumed from its last checkpoint replays exactly the generations an uninterrupted run would (same populations,
same fitness bits, same final state).

The loop's folder (a `jaxplan.core.run_folder.RunFolder`, `TUNE_LAYOUT`)::

    generations.csv                      one row per generation: evaluations so far, best so far, the
                                         generation's best / mean (finite values) / worst finite, how many
                                         fitness values were NaN/inf (counted, then treated as the worst),
                                         and the best-so-far weights by name; deterministic (no wall times)
    timings.csv                          wall-clock seconds of each generation's compiled evaluation
    checkpoints/manifest.json            the commit log: the run's fingerprint and its checkpoints
    checkpoints/generations/gen_NNNNN.*  a checkpoint's rows (generations.csv up to generation NNNNN) and record
    checkpoints/gen_NNNNN/               the strategy state after generation NNNNN (orbax), every k generations (the
                                         last two are kept)
    .lock                                held by the process that works in the folder

A checkpoint is an entry of the run folder: its rows and state are written, then the manifest names it, so a
process killed at any instant leaves at worst a checkpoint the manifest does not name, and the resume recomputes
those generations. A resume checks the rows and state it reads against their SHA-256; a checkpoint that is missing,
truncated or changed is dropped for the newest intact one before it (the generations after it are recomputed, to
the same bits), and a damaged manifest is rebuilt from the checkpoints' records — a note on stderr says which. A
folder of an earlier jaxplan (its manifest held the rows and the states' digests) is converted on the first resume.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.core.progress import ProgressBar
from jaxplan.core.run_folder import (
    MANIFEST,
    CheckpointError,
    Layout,
    Payload,
    RunFolder,
    RunFolderError,
    load_arrays,
)
from jaxplan.tune._base import Strategy, sanitize
from jaxplan.tune._objective import Objective

__all__ = ["TUNE_LAYOUT", "TuneResult", "tune_loop"]

TUNE_LAYOUT = Layout(table="generations", suffix=".csv", arrays="", noun="checkpoint",
                     refusal="a different tuning run (config, strategy, space or seed changed); delete that folder, "
                             "pass another out folder or resume=False")
"""Where a tuning run folder keeps its checkpoints (`jaxplan.core.run_folder.Layout`): rows in
``checkpoints/generations/gen_NNNNN.csv``, the state in ``checkpoints/gen_NNNNN/``."""

_FIELDS = ("state", "rows", "best_x", "best_f", "n_bad", "evaluations", "resumed_from")


@dataclasses.dataclass(frozen=True, eq=False)
class TuneResult:
    """What `tune_loop` returns.

    Attributes:
      state: the strategy's final state.
      rows: one dict per generation (the columns of generations.csv).
      best_x: ``f32[D]`` the best weights found.
      best_f: their training fitness.
      n_bad: NaN/inf fitness values over all generations.
      evaluations: weight vectors evaluated (generations × population).
      resumed_from: the generation the run resumed from (0: from the start).

    Mapping access (``result["rows"]``) works for one release, with a `DeprecationWarning`: use the attributes.
    """

    state: Any
    rows: list[dict]
    best_x: np.ndarray
    best_f: float
    n_bad: int
    evaluations: int
    resumed_from: int

    def _warn(self) -> None:
        warnings.warn("TuneResult is no longer a dict: use its attributes (result.rows, not result['rows'])",
                      DeprecationWarning, stacklevel=3)

    def __getitem__(self, key: str) -> Any:
        self._warn()
        if key not in _FIELDS:
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        """Deprecated mapping access (`TuneResult`)."""
        self._warn()
        return getattr(self, key) if key in _FIELDS else default

    def keys(self) -> tuple[str, ...]:
        """Deprecated mapping access (`TuneResult`)."""
        self._warn()
        return _FIELDS

    def items(self) -> list[tuple[str, Any]]:
        """Deprecated mapping access (`TuneResult`)."""
        self._warn()
        return [(k, getattr(self, k)) for k in _FIELDS]

    def values(self) -> list[Any]:
        """Deprecated mapping access (`TuneResult`)."""
        self._warn()
        return [getattr(self, k) for k in _FIELDS]

    def __contains__(self, key: object) -> bool:
        self._warn()
        return key in _FIELDS

    def __iter__(self) -> Iterator[str]:
        self._warn()
        return iter(_FIELDS)

    def __len__(self) -> int:
        return len(_FIELDS)


def _columns(names) -> list[str]:
    return ["generation", "evaluations", "best", "gen_best", "gen_mean", "gen_worst", "n_bad"] + list(names)


_INT_COLUMNS = ("generation", "evaluations", "n_bad")


def _csv(rows: list[dict], names) -> bytes:
    cols = _columns(names)
    buf = io.StringIO()
    buf.write(",".join(cols) + "\n")
    for r in rows:
        buf.write(",".join(repr(r[c]) if isinstance(r[c], float) else str(r[c]) for c in cols) + "\n")
    return buf.getvalue().encode()


def _parse_csv(data: bytes, names) -> list[dict]:
    """The rows `_csv` wrote (floats are written with ``repr``, so they read back to the same bits).

    Raises:
      ValueError: the header is not this run's.
    """
    lines = data.decode().splitlines()
    cols = _columns(names)
    if not lines or lines[0].split(",") != cols:
        raise ValueError("holds the rows of another search space")
    return [{c: int(v) if c in _INT_COLUMNS else float(v) for c, v in zip(cols, ln.split(","), strict=True)}
            for ln in lines[1:]]


def _state_arrays(state) -> dict[str, np.ndarray]:
    """The state's leaves as ``{"leaf_0000": array, …}`` (typed PRNG keys as their raw data)."""
    data = {}
    for i, a in enumerate(jax.tree_util.tree_leaves(state)):
        a = jnp.asarray(a)
        if jnp.issubdtype(a.dtype, jax.dtypes.prng_key):
            a = jax.random.key_data(a)
        data[f"leaf_{i:04d}"] = np.asarray(a)
    return data


def _restore_state(data: Mapping[str, np.ndarray], template):
    """``template``'s tree with the leaves of ``data`` (`_state_arrays`).

    Raises:
      ValueError: ``data`` holds another state (other leaves).
    """
    leaves, treedef = jax.tree_util.tree_flatten(template)
    if set(data) != {f"leaf_{i:04d}" for i in range(len(leaves))}:
        raise ValueError("holds another state")
    out = []
    for i, t in enumerate(leaves):
        a = np.asarray(data[f"leaf_{i:04d}"])
        t = jnp.asarray(t)
        out.append(jax.random.wrap_key_data(a) if jnp.issubdtype(t.dtype, jax.dtypes.prng_key)
                   else jnp.asarray(a, t.dtype))
    return jax.tree_util.tree_unflatten(treedef, out)


def _gen_name(g: int) -> str:
    return f"gen_{g:05d}"


class _Progress:
    """The tuning bar: generations done of ``total``, the best fitness so far, elapsed and time left
    (`jaxplan.core.progress`; drawn only on a terminal). The first generation includes compiling the objective."""

    def __init__(self, name: str, total: int, enabled: bool, done: int = 0):
        self.name = name
        self.bar = ProgressBar(f"{name}: generation {done + 1} (compiling)", total, done=done, unit="generations",
                               enabled=enabled)

    def update(self, row: dict, eval_s: float) -> None:
        bad = f", {row['n_bad']} NaN/inf" if row["n_bad"] else ""
        text = f"{self.name}: best {row['best']:.5g} (mean {row['gen_mean']:.4g}{bad})"
        self.bar.update(row["generation"], description=text)

    def close(self) -> None:
        self.bar.close()


def tune_loop(objective: Objective, strategy: Strategy, generations: int, run_dir: str | Path, *, seed: int = 0,
              checkpoint_every: int = 2, resume: bool = True, progress: bool = True, fingerprint: str = "",
              x0: Any = "defaults", callback: Callable[[int, dict], None] | None = None) -> TuneResult:
    """Runs ``generations`` generations of ``strategy`` on the training split of ``objective``.

    The run folder is locked for the call (`jaxplan.core.run_folder.RunFolder.lock`; a caller that holds it
    already, as `run_tuning` does, keeps it).

    Args:
      objective: the `Objective` (each generation's population is one compiled call).
      strategy: a `Strategy`.
      generations: G >= 1.
      run_dir: the folder for generations.csv, timings.csv and checkpoints/.
      seed: PRNG seed; generation g uses ``fold_in(key(seed), g)``.
      checkpoint_every: k >= 1; a checkpoint after every k-th generation and after the last.
      resume: continue from the folder's last checkpoint (same fingerprint) instead of starting over.
      fingerprint: identifies the run; a folder holding another run's checkpoints is refused.
      x0: the strategies' starting point: ``"defaults"`` (the paper's weights), None (box centre) or ``f32[D]``.
      callback: ``callback(generation, row)`` after each generation (before its checkpoint).

    Returns:
      `TuneResult`.

    Raises:
      RunFolderError: the folder holds a different run's checkpoints (and ``resume`` is True).
      FolderInUseError: another process works in the folder.
    """
    if not isinstance(generations, int) or generations < 1:
        raise ValueError(f"generations must be a positive integer, got {generations!r}")
    if not isinstance(checkpoint_every, int) or checkpoint_every < 1:
        raise ValueError(f"checkpoint_every must be a positive integer, got {checkpoint_every!r}")
    run_dir = Path(run_dir)
    b = objective.bounds
    fp = hashlib.sha256(f"{fingerprint}|{strategy.name}|{strategy.population_size}|{generations}|{seed}|"
                        f"{b.names}|{b.low.tolist()}|{b.high.tolist()}".encode()).hexdigest()
    root = jax.random.key(seed)
    start = x0 if not (isinstance(x0, str) and x0 == "defaults") else objective.defaults
    state = strategy.init(jax.random.fold_in(root, 2**31 - 1), b, start)
    with RunFolder.lock(run_dir):
        legacy = _legacy_checkpoints(run_dir, fp, b.names) if resume else []
        with RunFolder.open(run_dir, fp, TUNE_LAYOUT, fresh=not resume) as folder:
            for g, payload in legacy:
                folder.commit(_gen_name(g), payload)
            if legacy:
                folder.notes.append(f"converted {len(legacy)} checkpoint{'s' if len(legacy) != 1 else ''} of an "
                                    "earlier jaxplan")
            folder.verify()
            state, g0, rows, times = _resume(folder, state, b.names)
            for line in folder.notes:
                _note(run_dir.name, line)
            return _generations(objective, strategy, generations, folder, root, state, g0, rows, times,
                                checkpoint_every, progress, callback)


def _generations(objective: Objective, strategy: Strategy, generations: int, folder: RunFolder, root, state, g0: int,
                 rows: list[dict], times: list[str], checkpoint_every: int, progress: bool,
                 callback: Callable[[int, dict], None] | None) -> TuneResult:
    """Generations ``g0 + 1 .. generations`` of `tune_loop`, committed to ``folder`` every ``checkpoint_every``."""
    b = objective.bounds
    ask, tell = jax.jit(strategy.ask), jax.jit(strategy.tell)
    prog = _Progress(folder.path.name, generations, progress, g0)
    P = strategy.population_size
    n_bad_total = sum(r["n_bad"] for r in rows)

    def commit(g: int) -> None:
        folder.commit(_gen_name(g), Payload(_csv(rows, b.names), _state_arrays(state),
                                            {"generation": g, "times": list(times)}))
        for name, entry in list(folder.entries.items()):  # keep the last two checkpoints
            if entry.get("generation", 0) < g - checkpoint_every:
                folder.discard(name)

    try:
        for g in range(g0, generations):
            pop = ask(jax.random.fold_in(root, g), state)
            ev = objective.evaluate(pop, "train")
            fit, n_bad = sanitize(jnp.asarray(ev.fitness))
            state = tell(state, pop, jnp.asarray(ev.fitness))
            raw = np.asarray(ev.fitness, np.float64)
            finite = raw[np.isfinite(raw)]
            n_bad_total += int(n_bad)
            bx = np.asarray(state.best_x, np.float64)
            row = {"generation": g + 1, "evaluations": (g + 1) * P, "best": float(state.best_f),
                   "gen_best": float(finite.min()) if finite.size else math.nan,
                   "gen_mean": float(finite.mean()) if finite.size else math.nan,
                   "gen_worst": float(finite.max()) if finite.size else math.nan, "n_bad": int(n_bad),
                   **{n: float(v) for n, v in zip(b.names, bx, strict=True)}}
            rows.append(row)
            times.append(f"{g + 1},{ev.time_s!r},{ev.compile_s!r}")
            folder.write("generations.csv", _csv(rows, b.names))
            folder.write("timings.csv", ("generation,eval_s,compile_s\n" + "\n".join(times) + "\n").encode())
            prog.update(row, ev.time_s)
            if callback is not None:
                callback(g + 1, row)
            if (g + 1) % checkpoint_every == 0 or g + 1 == generations:
                commit(g + 1)
    finally:
        prog.close()
    return TuneResult(state=state, rows=rows, best_x=np.asarray(state.best_x), best_f=float(state.best_f),
                      n_bad=n_bad_total, evaluations=generations * P, resumed_from=g0)


def _note(name: str, text: str) -> None:
    print(f"{name}: {text}", file=sys.stderr, flush=True)


def _resume(folder: RunFolder, template, names) -> tuple[Any, int, list[dict], list[str]]:
    """(state, generation, rows, timing lines) of the newest intact checkpoint in ``folder`` (one that cannot be read
    is dropped, with a note); (template, 0, [], []) if none is."""
    newest = sorted(folder.entries.items(), key=lambda kv: kv[1].get("generation", 0), reverse=True)
    for name, entry in newest:
        try:
            state = _restore_state(folder.arrays(name), template)
            rows = _parse_csv(folder.data(name), names)
        except (CheckpointError, ValueError) as e:
            folder.drop(name, f"{e}; falling back to an earlier one")
            continue
        g = int(entry["generation"])
        return state, g, rows[:g], list(entry.get("times", []))[:g]
    return template, 0, [], []


def _tree_digest(data: Mapping[str, np.ndarray]) -> str:
    """SHA-256 of a state's leaves (names, dtypes, shapes and bytes): how earlier versions checked a checkpoint."""
    h = hashlib.sha256()
    for k in sorted(data):
        a = np.ascontiguousarray(np.asarray(data[k]))
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _legacy_checkpoints(run_dir: Path, fp: str, names) -> list[tuple[int, Payload]]:
    """The intact checkpoints of a folder written by an earlier jaxplan, as payloads to commit; its manifest (which
    held the rows and the states' digests) is then removed. [] for any other folder.

    Raises:
      RunFolderError: the folder holds another run's checkpoints.
    """
    path = run_dir / MANIFEST
    try:
        old = json.loads(path.read_bytes().decode("utf-8"))
    except (OSError, ValueError):
        return []
    if not (isinstance(old, dict) and "version" not in old and isinstance(old.get("digests"), dict)
            and isinstance(old.get("rows"), list) and isinstance(old.get("generation"), int)):
        return []
    if old.get("fingerprint") != fp:
        raise RunFolderError(f"{run_dir} holds the checkpoints of {TUNE_LAYOUT.refusal}")
    out = []
    for key, digest in old["digests"].items():
        g = int(key)
        if not 0 < g <= min(old["generation"], len(old["rows"])):
            continue
        try:
            data = load_arrays(run_dir / "checkpoints" / _gen_name(g))
        except CheckpointError:
            continue
        if _tree_digest(data) == digest:
            out.append((g, Payload(_csv(old["rows"][:g], names), data,
                                   {"generation": g, "times": list(old.get("times", []))[:g]})))
    path.unlink()
    return sorted(out, key=lambda x: x[0])
