"""The run folder's checkpoint store: finished chunks, the manifest that commits them, and ``meta.json``.

A finished chunk is committed in four steps: its rows are written to ``chunks/ID.csv``
(`jaxplan.core.io.atomic_write`: temporary file, fsync, `os.replace`), its arrays saved with
orbax, its record written beside the rows (``chunks/ID.json``), and only then is its entry added
to ``manifest.json`` (again written atomically). The manifest is the single commit point: a
process killed at any instant (SIGKILL included) leaves at worst a chunk that is not in the
manifest, which the next run recomputes and overwrites. Restarting with the same config skips
every chunk in the manifest. The manifest holds the experiment's
`jaxplan.experiments.prepare.fingerprint`: a folder written by a different experiment is refused
(`RunFolderError`) rather than silently mixed. Each manifest entry records the session (1 for the
first invocation, 2 for the first restart, …) that computed it.

Integrity. Each entry holds the SHA-256 of the chunk's rows and of its array files. On resume every
committed chunk is checked against them (a file edited to the same size included), and once more as
the rows are merged into ``trials.csv``; a chunk that fails, or whose arrays are missing, is
recomputed — never merged. A manifest that is damaged, emptied or deleted is rebuilt from the
chunks' own records (``chunks/ID.json``: the fingerprint and the entry), keeping every chunk whose
rows and arrays still match; `notes` says what was done, for the progress output.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Sequence

import numpy as np

from jaxplan.core.io import TMP_GLOB, atomic_write
from jaxplan.experiments.config import ExperimentConfig
from jaxplan.experiments.prepare import Unit, sha256

__all__ = ["MANIFEST_VERSION", "RunFolderError", "CheckpointError", "Store", "read_manifest", "load_chunk_arrays",
           "arrays_digest", "seed_ranges", "write_meta"]

MANIFEST_VERSION = 1


class RunFolderError(ValueError):
    """The run folder holds a different experiment."""


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be written or read back (orbax), naming its path and what to do."""


def _manifest_problem(doc) -> str | None:
    """Why a parsed manifest is unusable (None if it is a manifest)."""
    if not isinstance(doc, dict):
        return "not a JSON object"
    if not isinstance(doc.get("fingerprint"), str):
        return "no fingerprint"
    if not isinstance(doc.get("chunks"), dict) or not all(isinstance(e, dict) for e in doc["chunks"].values()):
        return "no chunk table"
    if not isinstance(doc.get("sessions"), int):
        return "no session count"
    return None


def _load_manifest(path: Path) -> tuple[dict | None, str | None]:
    """(the manifest, None), or (None, why it is damaged), or (None, None) when there is none."""
    if not path.is_file():
        return None, None
    try:
        doc = json.loads(path.read_bytes().decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        return None, f"not valid JSON ({type(e).__name__})"
    problem = _manifest_problem(doc)
    return (doc, None) if problem is None else (None, problem)


def _records(run_dir: Path, fp: str) -> dict[str, dict]:
    """The chunks' own records (``chunks/ID.json``) written for fingerprint ``fp`` whose rows still match."""
    chunks = run_dir / "checkpoints" / "chunks"
    out = {}
    for p in sorted(chunks.glob("*.json")):
        try:
            rec = json.loads(p.read_bytes().decode("utf-8"))
            uid, entry = rec["uid"], rec["entry"]
            ok = rec["fingerprint"] == fp and isinstance(entry, dict) and p.stem == uid
        except (OSError, ValueError, KeyError, TypeError):
            continue
        csv = chunks / f"{uid}.csv"
        if ok and csv.is_file() and sha256(csv.read_bytes()) == entry.get("sha256"):
            out[uid] = entry
    return out


def _rebuilt(run_dir: Path, fp: str) -> dict:
    entries = _records(run_dir, fp)
    sessions = max((int(e.get("session", 0)) for e in entries.values()), default=0)
    return {"version": MANIFEST_VERSION, "fingerprint": fp, "sessions": sessions, "chunks": entries}


def read_manifest(run_dir: str | os.PathLike, fingerprint: str | None = None) -> dict:
    """The manifest of a run folder: ``{"fingerprint", "sessions", "chunks": {uid: entry}}``.

    A damaged or missing manifest is rebuilt in memory from the chunks' records when the experiment's
    ``fingerprint`` is given (`jaxplan.experiments.prepare.fingerprint`); without it a missing one is empty.

    Raises:
      RunFolderError: the manifest is damaged and no fingerprint was given to rebuild it.
    """
    run_dir = Path(run_dir)
    path = run_dir / "checkpoints" / "manifest.json"
    doc, problem = _load_manifest(path)
    if doc is not None:
        return doc
    if fingerprint is not None:
        return _rebuilt(run_dir, fingerprint)
    if problem is not None:
        raise RunFolderError(f"{path} is damaged ({problem}); run `jaxplan run CONFIG` with the run's config again: "
                             f"it rebuilds the manifest from the intact chunks")
    return {"chunks": {}, "sessions": 0}


def arrays_digest(folder: Path) -> str | None:
    """SHA-256 over the files (relative path and bytes) of a chunk's orbax folder; None if it has no files."""
    if not folder.is_dir():
        return None
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    if not files:
        return None
    h = hashlib.sha256()
    for p in files:
        h.update(p.relative_to(folder).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(p.read_bytes()).digest())
    return h.hexdigest()


class Store:
    """The run folder's checkpoint store (see the module docstring); opening it starts a new session.

    Attributes:
      notes: what opening (and merging) found and did: a rebuilt manifest, chunks that failed their
        checksum and are recomputed. One line each, for stderr.
    """

    def __init__(self, run_dir: Path, fp: str):
        self.dir = run_dir
        self.ck = run_dir / "checkpoints"
        self.chunks = self.ck / "chunks"
        self.arrays = self.ck / "arrays"
        self.fp = fp
        self.notes: list[str] = []
        for d in (self.chunks, self.arrays):
            d.mkdir(parents=True, exist_ok=True)
        self.path = self.ck / "manifest.json"
        # Leftovers of a killed writer: our temporary files and orbax's unfinished saves.
        for p in list(self.chunks.glob(TMP_GLOB)) + list(self.ck.glob(TMP_GLOB)):
            p.unlink(missing_ok=True)
        for p in self.arrays.glob("*.orbax-checkpoint-tmp*"):
            shutil.rmtree(p, ignore_errors=True)
        doc, problem = _load_manifest(self.path)
        if doc is not None and doc["fingerprint"] != fp:
            raise RunFolderError(
                f"{run_dir} holds the checkpoints of a different experiment (seeds, chunk size, maps, "
                "scenarios, planners or metrics changed); delete that folder or pass another --out")
        if doc is None:
            doc = _rebuilt(run_dir, fp)
            if problem is not None or doc["chunks"]:
                why = f"was damaged ({problem})" if problem is not None else "was missing"
                self.notes.append(f"{self.path} {why}: rebuilt from {len(doc['chunks'])} intact chunk"
                                  f"{'s' if len(doc['chunks']) != 1 else ''}")
        self.manifest = doc
        self.manifest["sessions"] += 1
        self.session = self.manifest["sessions"]
        self._save()

    def _save(self) -> None:
        atomic_write(self.path, json.dumps(self.manifest, indent=1, sort_keys=True).encode())

    def _problem(self, u: Unit, entry: dict) -> str | None:
        """Why committed chunk ``u`` cannot be used as it is on disk (None if intact)."""
        f = self.chunks / f"{u.uid}.csv"
        if not f.is_file():
            return "its rows are missing"
        data = f.read_bytes()
        if len(data) != entry.get("bytes") or sha256(data) != entry.get("sha256"):
            return "its rows fail their SHA-256 check (the file was changed)"
        if entry.get("arrays"):
            a = self.arrays / u.uid
            if not a.is_dir():
                return "its arrays are missing"
            want = entry.get("arrays_sha256")
            if want is not None and arrays_digest(a) != want:
                return "its arrays fail their SHA-256 check (a file was changed or truncated)"
        return None

    def _drop(self, u: Unit, why: str) -> None:
        del self.manifest["chunks"][u.uid]
        self.notes.append(f"chunk {u.uid}: {why}; recomputing it")
        self._save()

    def verify(self, units: Sequence[Unit]) -> list[Unit]:
        """Checks every committed chunk of ``units`` (rows and arrays against their SHA-256); a chunk that
        fails is removed from the manifest (so it is recomputed) and returned."""
        bad = []
        for u in units:
            e = self.manifest["chunks"].get(u.uid)
            if e is not None:
                why = self._problem(u, e)
                if why is not None:
                    self._drop(u, why)
                    bad.append(u)
        return bad

    def done(self, u: Unit) -> bool:
        """Chunk ``u`` is committed (`verify` has checked it on this session's start)."""
        return u.uid in self.manifest["chunks"]

    def commit(self, u: Unit, info: dict, text: str, arrays: dict, timing: dict) -> None:
        data = text.encode()
        atomic_write(self.chunks / f"{u.uid}.csv", data)
        arrays = {k: np.asarray(v) for k, v in arrays.items() if np.asarray(v).size}
        digest = None
        if arrays:
            import orbax.checkpoint as ocp

            target = (self.arrays / u.uid).resolve()
            try:
                ocp.PyTreeCheckpointer().save(target, arrays, force=True)
            except OSError:
                raise
            except Exception as e:  # noqa: BLE001 - orbax's and tensorstore's own errors: one clear message
                raise CheckpointError(f"cannot save the arrays of chunk {u.uid} to {target}: {type(e).__name__}: "
                                      f"{str(e).splitlines()[0] if str(e) else ''}; check the disk, then run the "
                                      f"same command to resume") from e
            digest = arrays_digest(self.arrays / u.uid)
        entry = {**info, "bytes": len(data), "sha256": sha256(data), "session": self.session,
                 "arrays": sorted(arrays), **timing}
        if digest is not None:
            entry["arrays_sha256"] = digest
        record = {"uid": u.uid, "fingerprint": self.fp, "entry": entry}
        atomic_write(self.chunks / f"{u.uid}.json", json.dumps(record, indent=1, sort_keys=True).encode())
        self.manifest["chunks"][u.uid] = entry
        self._save()

    def merged(self, units: Sequence[Unit], header: str) -> bytes | None:
        """The header and every chunk's rows in run order, each checked against its SHA-256 as it is read;
        None (the failing chunks dropped from the manifest, to be recomputed) if any fails."""
        parts, ok = [header.encode()], True
        for u in units:
            f = self.chunks / f"{u.uid}.csv"
            data = f.read_bytes() if f.is_file() else None
            entry = self.manifest["chunks"].get(u.uid, {})
            if data is None or sha256(data) != entry.get("sha256"):
                self._drop(u, "its rows changed after the check at start-up" if data is not None
                           else "its rows are missing")
                ok = False
                continue
            parts.append(data)
        return b"".join(parts) if ok else None


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
    import orbax.checkpoint as ocp

    folder = (Path(run_dir) / "checkpoints" / "arrays" / uid).resolve()
    if not folder.is_dir():
        raise CheckpointError(f"the arrays of chunk {uid} are missing ({folder})")
    if expected_sha256 is not None and arrays_digest(folder) != expected_sha256:
        raise CheckpointError(f"the arrays of chunk {uid} fail their SHA-256 check ({folder}: a file was changed or "
                              f"truncated)")
    try:
        return ocp.PyTreeCheckpointer().restore(folder)
    except Exception as e:  # noqa: BLE001 - orbax's, tensorstore's and JSON errors of a damaged checkpoint
        raise CheckpointError(f"the arrays of chunk {uid} cannot be read ({folder}: {type(e).__name__})") from e


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
