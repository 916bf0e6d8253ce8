"""Run folders: the one way jaxplan keeps resumable work on disk (`jaxplan run`, `jaxplan tune`, `jaxplan study`).

A run folder is written by one process at a time (`RunFolder.open` holds `jaxplan.core.io.folder_lock`). Its
finished work is a table of named entries (an experiment's chunks, a tuning run's checkpoints, a study's runs),
each committed in four steps: the entry's data (its rows: CSV or JSON bytes) is written to
``checkpoints/TABLE/NAME.SUFFIX``, its arrays are saved with orbax, its record (the fingerprint and the entry) is
written beside the data (``checkpoints/TABLE/NAME.json``), and only then is the entry added to
``checkpoints/manifest.json``. Every file is written with `jaxplan.core.io.atomic_write` (temporary file, fsync,
`os.replace`), so the manifest is the single commit point: a process killed at any instant (SIGKILL included) leaves
at worst an entry the manifest does not name, which the next session recomputes and overwrites::

    .lock                           held by the writing process (`jaxplan.core.io.folder_lock`)
    checkpoints/manifest.json       {"version", "fingerprint", "sessions", TABLE: {NAME: entry}}
    checkpoints/TABLE/NAME.SUFFIX   an entry's data
    checkpoints/TABLE/NAME.json     its record: rebuilds a damaged manifest
    checkpoints/ARRAYS/NAME/        its arrays (orbax), when it has any

The table's name, the data's suffix and the arrays' folder are the folder's `Layout`.

Fingerprint. The manifest holds a fingerprint of everything that shapes the work (the caller's): a folder written
with another fingerprint is refused (`RunFolderError`) rather than silently mixed.

Integrity. An entry holds the size and SHA-256 of its data and the SHA-256 of its array files (`arrays_digest`).
`RunFolder.verify` checks committed entries against them (a file edited to the same size included) and drops the
entries that fail, so they are recomputed, never used; `RunFolder.data` and `RunFolder.merged` check the data again
as they read it. A manifest that is damaged, emptied or deleted is rebuilt from the entries' own records, keeping
every entry whose data still matches; `RunFolder.notes` says what was done, one line each, for stderr.

Sessions. Opening a folder for writing starts a session (1 for the first process, 2 for the first resume, …); each
entry records the session that computed it, and `RunFolder.log_session` keeps one record per session in a JSON list.

Work done elsewhere. `Payload` is what one unit of work returns — its data, arrays and JSON fields — and
`RunFolder.commit` takes it as it is, so a unit may run in another process or on another machine while the process
that holds the folder stays its only writer.

Imports nothing from jaxplan above `jaxplan.core`; orbax is imported when arrays are saved or read.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from jaxplan.core.io import TMP_GLOB, atomic_write, folder_lock

__all__ = ["MANIFEST_VERSION", "MANIFEST", "RunFolderError", "CheckpointError", "Layout", "Payload", "RunFolder",
           "sha256", "arrays_digest", "save_arrays", "load_arrays", "load_manifest", "rebuilt_manifest"]

MANIFEST_VERSION = 1
"""The manifest format this module writes (and the newest it reads)."""

MANIFEST = "checkpoints/manifest.json"
"""The manifest's path inside a run folder."""


class RunFolderError(ValueError):
    """The run folder holds different work (another fingerprint), or a manifest this version cannot use."""


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be written or read back (orbax), naming its path and what to do."""


def sha256(*chunks: bytes) -> str:
    """Hex SHA-256 of the concatenated byte strings."""
    h = hashlib.sha256()
    for c in chunks:
        h.update(c)
    return h.hexdigest()


def arrays_digest(folder: str | os.PathLike) -> str | None:
    """SHA-256 over the files (relative path and bytes) of an orbax folder; None if it has no files."""
    folder = Path(folder)
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


def save_arrays(folder: str | os.PathLike, arrays: Mapping[str, np.ndarray], what: str) -> str | None:
    """Saves ``arrays`` (name -> array) to ``folder`` with orbax; returns their `arrays_digest`.

    Raises:
      CheckpointError: orbax or tensorstore failed (naming ``what`` and the folder); an `OSError` passes as it is.
    """
    import orbax.checkpoint as ocp

    target = Path(folder).resolve()
    try:
        ocp.PyTreeCheckpointer().save(target, dict(arrays), force=True)
    except OSError:
        raise
    except Exception as e:  # noqa: BLE001 - orbax's and tensorstore's own errors: one clear message
        first = str(e).splitlines()[0] if str(e) else ""
        raise CheckpointError(f"cannot save {what} to {target}: {type(e).__name__}: {first}; check the disk, then run "
                              f"the same command to resume") from e
    return arrays_digest(target)


def load_arrays(folder: str | os.PathLike, expected_sha256: str | None = None, what: str = "the arrays"
                ) -> dict[str, np.ndarray]:
    """The arrays saved in ``folder`` (orbax), checked first against ``expected_sha256`` (`arrays_digest`) if given.

    Raises:
      CheckpointError: the folder is missing, fails its checksum or cannot be read (naming ``what`` and the folder).
    """
    import orbax.checkpoint as ocp

    folder = Path(folder).resolve()
    if not folder.is_dir():
        raise CheckpointError(f"{what} are missing ({folder})")
    if expected_sha256 is not None and arrays_digest(folder) != expected_sha256:
        raise CheckpointError(f"{what} fail their SHA-256 check ({folder}: a file was changed or truncated)")
    try:
        return ocp.PyTreeCheckpointer().restore(folder)
    except Exception as e:  # noqa: BLE001 - orbax's, tensorstore's and JSON errors of a damaged checkpoint
        raise CheckpointError(f"{what} cannot be read ({folder}: {type(e).__name__})") from e


@dataclasses.dataclass(frozen=True)
class Layout:
    """Where a kind of run folder keeps its entries (module docstring).

    Attributes:
      table: the manifest's key of the entries, and their folder under ``checkpoints/``.
      suffix: the data files' suffix.
      arrays: the folder of the entries' arrays under ``checkpoints/`` (``""``: ``checkpoints/NAME/`` itself).
      noun: what an entry is, for notes (``"chunk"``: "chunk 0003: its rows are missing; recomputing it").
      refusal: the end of the message that refuses a folder of another fingerprint (what changed, what to do).
    """

    table: str = "chunks"
    suffix: str = ".csv"
    arrays: str = "arrays"
    noun: str = "entry"
    refusal: str = "delete that folder or pass another --out"


@dataclasses.dataclass(frozen=True)
class Payload:
    """What one unit of work returns for the folder's writer to commit (picklable: it may come from another process
    or machine).

    Attributes:
      data: the entry's data (CSV rows, JSON), kept byte for byte and checked by its SHA-256.
      arrays: name -> array, kept with orbax (empty arrays are left out).
      info: JSON fields recorded in the manifest entry (labels, timings).
    """

    data: bytes
    arrays: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    info: Mapping[str, Any] = dataclasses.field(default_factory=dict)


def _manifest_problem(doc: Any, table: str) -> str | None:
    """Why a parsed manifest is unusable (None if it is a manifest)."""
    if not isinstance(doc, dict):
        return "not a JSON object"
    if not isinstance(doc.get("fingerprint"), str):
        return "no fingerprint"
    if not isinstance(doc.get(table), dict) or not all(isinstance(e, dict) for e in doc[table].values()):
        return f"no {table} table"
    if not isinstance(doc.get("sessions"), int):
        return "no session count"
    return None


def load_manifest(path: str | os.PathLike, table: str = "chunks") -> tuple[dict | None, str | None]:
    """(the manifest at ``path``, None), or (None, why it is damaged), or (None, None) when there is none.

    Raises:
      RunFolderError: the manifest was written by a newer jaxplan (its ``version`` is above `MANIFEST_VERSION`).
    """
    path = Path(path)
    if not path.is_file():
        return None, None
    try:
        doc = json.loads(path.read_bytes().decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        return None, f"not valid JSON ({type(e).__name__})"
    if isinstance(doc, dict) and isinstance(doc.get("version"), int) and doc["version"] > MANIFEST_VERSION:
        raise RunFolderError(f"{path} was written by a newer jaxplan (manifest version {doc['version']}, this one "
                             f"reads up to {MANIFEST_VERSION}); upgrade jaxplan or use another folder")
    problem = _manifest_problem(doc, table)
    return (doc, None) if problem is None else (None, problem)


def rebuilt_manifest(folder: str | os.PathLike, fingerprint: str, layout: Layout = Layout()) -> dict:
    """The manifest rebuilt from the entries' own records (``checkpoints/TABLE/NAME.json``) written for
    ``fingerprint`` whose data still matches its SHA-256; nothing is written. Its session count is the highest
    session of those entries."""
    table_dir = Path(folder) / "checkpoints" / layout.table
    entries = {}
    for p in sorted(table_dir.glob("*.json")):
        try:
            rec = json.loads(p.read_bytes().decode("utf-8"))
            name, entry = rec["uid"], rec["entry"]
            ok = rec["fingerprint"] == fingerprint and isinstance(entry, dict) and p.stem == name
        except (OSError, ValueError, KeyError, TypeError):
            continue
        data = table_dir / f"{name}{layout.suffix}"
        if ok and data.is_file() and sha256(data.read_bytes()) == entry.get("sha256"):
            entries[name] = entry
    sessions = max((int(e.get("session", 0)) for e in entries.values()), default=0)
    return {"version": MANIFEST_VERSION, "fingerprint": fingerprint, "sessions": sessions, layout.table: entries}


_HELD: dict[str, int] = {}
"""The folders whose lock this process holds (real path -> depth): `RunFolder.lock` is re-entrant."""


class RunFolder:
    """A run folder open for writing (module docstring); opening it starts a new session.

    Construct it with `RunFolder.open` (which holds the folder's lock), or directly while holding the lock.

    Attributes:
      path: the folder.
      fingerprint: the work's fingerprint (the manifest's).
      layout: where its entries live (`Layout`).
      session: this session's number (1 for the first).
      notes: what opening, verifying and merging found and did: a rebuilt manifest, entries that failed their
        checksum and are recomputed. One line each, for stderr.
    """

    def __init__(self, path: str | os.PathLike, fingerprint: str, layout: Layout = Layout(), *,
                 fresh: bool = False) -> None:
        """Opens the folder's manifest (rebuilding a damaged or missing one from the records) and starts a session.

        Args:
          path: the folder (created if missing).
          fingerprint: what the folder must hold; a manifest of another fingerprint is refused.
          layout: where the entries live.
          fresh: discard everything under ``checkpoints/`` first (start over).

        Raises:
          RunFolderError: the folder holds the work of another fingerprint, or a newer manifest.
        """
        self.path = Path(path)
        self.fingerprint = fingerprint
        self.layout = layout
        self.notes: list[str] = []
        self.checkpoints = self.path / "checkpoints"
        if fresh and self.checkpoints.exists():
            shutil.rmtree(self.checkpoints)
        self.table_dir = self.checkpoints / layout.table
        self.arrays_dir = self.checkpoints / layout.arrays if layout.arrays else self.checkpoints
        for d in (self.table_dir, self.arrays_dir):
            d.mkdir(parents=True, exist_ok=True)
        self.manifest_path = self.path / MANIFEST
        # Leftovers of a killed writer: our temporary files and orbax's unfinished saves.
        for p in list(self.table_dir.glob(TMP_GLOB)) + list(self.checkpoints.glob(TMP_GLOB)):
            p.unlink(missing_ok=True)
        for p in self.arrays_dir.glob("*.orbax-checkpoint-tmp*"):
            shutil.rmtree(p, ignore_errors=True)
        doc, problem = load_manifest(self.manifest_path, layout.table)
        if doc is not None and doc["fingerprint"] != fingerprint:
            raise RunFolderError(f"{self.path} holds the checkpoints of {layout.refusal}")
        if doc is None:
            doc = rebuilt_manifest(self.path, fingerprint, layout)
            n = len(doc[layout.table])
            if problem is not None or n:
                why = f"was damaged ({problem})" if problem is not None else "was missing"
                self.notes.append(f"{self.manifest_path} {why}: rebuilt from {n} intact {layout.noun}"
                                  f"{'s' if n != 1 else ''}")
        self.manifest = doc
        self.manifest["sessions"] += 1
        self.session: int = self.manifest["sessions"]
        self._earlier: dict[str, list[dict]] = {}
        self._save()

    @staticmethod
    @contextlib.contextmanager
    def lock(path: str | os.PathLike) -> Iterator[Path]:
        """Holds the lock of the folder ``path`` (created if missing) for the block (`jaxplan.core.io.folder_lock`).

        Re-entrant within a process: a block that already holds the folder's lock (a tuning run inside its study's
        run, the tuning loop inside `jaxplan tune`) holds it again at no cost; it is released when the outermost
        block ends.

        Raises:
          FolderInUseError: another process holds the folder's lock.
        """
        path = Path(path)
        path.mkdir(parents=True, exist_ok=True)
        key = os.path.realpath(path)
        if key in _HELD:
            _HELD[key] += 1
            try:
                yield path
            finally:
                _HELD[key] -= 1
            return
        with folder_lock(path):
            _HELD[key] = 1
            try:
                yield path
            finally:
                del _HELD[key]

    @classmethod
    @contextlib.contextmanager
    def open(cls, path: str | os.PathLike, fingerprint: str, layout: Layout = Layout(), *,
             fresh: bool = False) -> Iterator[RunFolder]:
        """The folder (created if missing) open for writing for the block, its lock held throughout (`lock`).

        Raises:
          FolderInUseError: another process holds the folder's lock.
          RunFolderError: as the constructor.
        """
        with cls.lock(path):
            yield cls(path, fingerprint, layout, fresh=fresh)

    # -- the manifest -------------------------------------------------------------------------------------------

    @property
    def entries(self) -> dict[str, dict]:
        """The committed entries, name -> entry (``bytes``, ``sha256``, ``session``, ``arrays``, the payload's info)."""
        return self.manifest[self.layout.table]

    def _save(self) -> None:
        atomic_write(self.manifest_path, json.dumps(self.manifest, indent=1, sort_keys=True).encode())

    def done(self, name: str) -> bool:
        """Entry ``name`` is committed."""
        return name in self.entries

    def data_path(self, name: str) -> Path:
        """Where entry ``name`` keeps its data."""
        return self.table_dir / f"{name}{self.layout.suffix}"

    def arrays_path(self, name: str) -> Path:
        """Where entry ``name`` keeps its arrays (orbax)."""
        return self.arrays_dir / name

    def problem(self, name: str) -> str | None:
        """Why committed entry ``name`` cannot be used as it is on disk (None if intact)."""
        entry = self.entries[name]
        f = self.data_path(name)
        if not f.is_file():
            return "its rows are missing"
        data = f.read_bytes()
        if len(data) != entry.get("bytes") or sha256(data) != entry.get("sha256"):
            return "its rows fail their SHA-256 check (the file was changed)"
        if entry.get("arrays"):
            a = self.arrays_path(name)
            if not a.is_dir():
                return "its arrays are missing"
            want = entry.get("arrays_sha256")
            if want is not None and arrays_digest(a) != want:
                return "its arrays fail their SHA-256 check (a file was changed or truncated)"
        return None

    def drop(self, name: str, why: str) -> None:
        """Removes entry ``name`` from the manifest (it is recomputed), noting ``why``; its files stay until then."""
        del self.entries[name]
        self.notes.append(f"{self.layout.noun} {name}: {why}; recomputing it")
        self._save()

    def verify(self, names: Sequence[str] | None = None) -> list[str]:
        """Checks the committed entries among ``names`` (default: all) against their SHA-256; an entry that fails is
        dropped from the manifest (so it is recomputed) and returned."""
        bad = []
        for name in list(self.entries) if names is None else names:
            if name in self.entries:
                why = self.problem(name)
                if why is not None:
                    self.drop(name, why)
                    bad.append(name)
        return bad

    def commit(self, name: str, payload: Payload) -> dict:
        """Commits ``payload`` as entry ``name`` (data, arrays, record, then the manifest); returns the entry.

        Raises:
          CheckpointError: the arrays cannot be saved (orbax).
        """
        data = bytes(payload.data)
        atomic_write(self.data_path(name), data)
        arrays = {k: np.asarray(v) for k, v in payload.arrays.items() if np.asarray(v).size}
        digest = None
        if arrays:
            digest = save_arrays(self.arrays_path(name), arrays, f"the arrays of {self.layout.noun} {name}")
        entry = {**payload.info, "bytes": len(data), "sha256": sha256(data), "session": self.session,
                 "arrays": sorted(arrays)}
        if digest is not None:
            entry["arrays_sha256"] = digest
        record = {"uid": name, "fingerprint": self.fingerprint, "entry": entry}
        atomic_write(self.table_dir / f"{name}.json", json.dumps(record, indent=1, sort_keys=True).encode())
        self.entries[name] = entry
        self._save()
        return entry

    def discard(self, name: str) -> None:
        """Removes entry ``name`` from the manifest, then its files (a superseded checkpoint)."""
        if self.entries.pop(name, None) is not None:
            self._save()
        for p in (self.data_path(name), self.table_dir / f"{name}.json"):
            p.unlink(missing_ok=True)
        shutil.rmtree(self.arrays_path(name), ignore_errors=True)

    # -- reading entries ----------------------------------------------------------------------------------------

    def data(self, name: str) -> bytes:
        """The data of committed entry ``name``, checked against its SHA-256 as it is read.

        Raises:
          CheckpointError: the entry is not committed, or its data is missing or changed.
        """
        entry = self.entries.get(name)
        f = self.data_path(name)
        data = f.read_bytes() if entry is not None and f.is_file() else None
        if data is None or sha256(data) != entry.get("sha256"):
            raise CheckpointError(f"{self.layout.noun} {name}: its rows are missing or changed ({f})")
        return data

    def arrays(self, name: str) -> dict[str, np.ndarray]:
        """The arrays of committed entry ``name``, checked against their SHA-256 (`load_arrays`)."""
        entry = self.entries.get(name, {})
        return load_arrays(self.arrays_path(name), entry.get("arrays_sha256"),
                           f"the arrays of {self.layout.noun} {name}")

    def merged(self, names: Sequence[str], head: bytes = b"") -> bytes | None:
        """``head`` and the data of every entry in ``names``, in that order, each checked as it is read; None (the
        failing entries dropped from the manifest, to be recomputed) if any fails."""
        parts, ok = [head], True
        for name in names:
            try:
                parts.append(self.data(name))
            except CheckpointError:
                exists = self.data_path(name).is_file()
                self.drop(name, "its rows changed after the check at start-up" if exists else "its rows are missing")
                ok = False
        return b"".join(parts) if ok else None

    # -- other files --------------------------------------------------------------------------------------------

    def write(self, name: str, data: bytes | str) -> Path:
        """Writes the folder's file ``name`` (a path relative to the folder) atomically; returns its path."""
        return atomic_write(self.path / name, data)

    def log_session(self, name: str, record: Mapping[str, Any], earlier: Sequence[Mapping[str, Any]] | None = None
                    ) -> list[dict]:
        """Writes the JSON list ``name``: the earlier sessions' records, then ``record`` for this session, replacing
        what this session wrote there before. Returns the list.

        Args:
          earlier: the records before this session; default: the file's, as this session first found it (a
            missing or damaged file: none).
        """
        if name not in self._earlier:
            if earlier is None:
                try:
                    earlier = json.loads((self.path / name).read_text())
                except (OSError, ValueError):
                    earlier = []
                earlier = earlier if isinstance(earlier, list) else []
            self._earlier[name] = [dict(x) for x in earlier]
        out = self._earlier[name] + [dict(record)]
        self.write(name, json.dumps(out, indent=1).encode())
        return out
