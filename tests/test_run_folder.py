"""The one run folder (`jaxplan.core.run_folder`): commits through the manifest, SHA-256 checks, rebuilds, sessions,
the lock, and payloads computed in another process."""

from __future__ import annotations

import json
import pickle
import subprocess
import sys

import numpy as np
import pytest

from jaxplan.core.io import FolderInUseError
from jaxplan.core.run_folder import (
    MANIFEST,
    CheckpointError,
    Layout,
    Payload,
    RunFolder,
    RunFolderError,
    load_manifest,
    rebuilt_manifest,
)

LAYOUT = Layout(table="parts", suffix=".csv", arrays="arrays", noun="part", refusal="other work; use another folder")


def _payload(i: int) -> Payload:
    return Payload(f"a,b\n{i},{i * 0.1!r}\n".encode(), {"x": np.arange(i + 3, dtype=np.float32), "empty": np.zeros(0)},
                   {"label": f"p{i}", "time_s": 0.5 * i})


def _square(i: int) -> Payload:  # a unit of work run in another process (module level: picklable)
    return _payload(i)


def test_commit_then_reopen_reads_every_entry_back_and_counts_sessions(tmp_path):
    with RunFolder.open(tmp_path / "f", "fp", LAYOUT) as f:
        assert f.session == 1 and f.entries == {}
        for i in range(3):
            entry = f.commit(f"u{i}", _payload(i))
            assert entry["label"] == f"p{i}" and entry["session"] == 1 and entry["arrays"] == ["x"]
    with RunFolder.open(tmp_path / "f", "fp", LAYOUT) as f:
        assert f.session == 2 and sorted(f.entries) == ["u0", "u1", "u2"]
        assert f.verify() == [] and f.notes == []
        assert f.data("u1") == _payload(1).data
        np.testing.assert_array_equal(f.arrays("u2")["x"], np.arange(5, dtype=np.float32))
        assert f.merged(["u2", "u0"], b"head\n") == b"head\n" + _payload(2).data + _payload(0).data
    doc, problem = load_manifest(tmp_path / "f" / MANIFEST, "parts")
    assert problem is None and doc["sessions"] == 2 and doc["version"] == 1


def test_changed_rows_or_arrays_are_dropped_and_recomputed_never_used(tmp_path):
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        for i in range(3):
            f.commit(f"u{i}", _payload(i))
    rows = tmp_path / "checkpoints" / "parts" / "u0.csv"
    rows.write_bytes(rows.read_bytes().replace(b"0,", b"9,"))  # same size, other bytes
    for p in (tmp_path / "checkpoints" / "arrays" / "u1").rglob("*"):
        if p.is_file():
            p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        assert f.verify() == ["u0", "u1"] and sorted(f.entries) == ["u2"]
        assert "part u0: its rows fail their SHA-256 check" in f.notes[0] and "recomputing it" in f.notes[0]
        assert "part u1: its arrays fail their SHA-256 check" in f.notes[1]
        with pytest.raises(CheckpointError, match="part u0"):
            f.data("u0")
        f.commit("u0", _payload(0))
        assert f.entries["u0"]["session"] == 2
    rows.write_bytes(b"changed after the check\n")
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        assert f.merged(["u0", "u2"]) is None and "u0" not in f.entries  # checked again as it is read


@pytest.mark.parametrize("damage", [b"{", b"{}", b"[]", None])
def test_a_damaged_or_lost_manifest_is_rebuilt_from_the_records(tmp_path, damage):
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        f.commit("u0", _payload(0))
        f.commit("u1", _payload(1))
    (tmp_path / "checkpoints" / "parts" / "u1.csv").write_bytes(b"edited")  # not rebuilt: its rows changed
    m = tmp_path / MANIFEST
    m.unlink() if damage is None else m.write_bytes(damage)
    assert sorted(rebuilt_manifest(tmp_path, "fp", LAYOUT)["parts"]) == ["u0"]
    assert rebuilt_manifest(tmp_path, "other", LAYOUT)["parts"] == {}
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        assert sorted(f.entries) == ["u0"] and f.session == 2  # the sessions of the rebuilt entries, then this one
        why = "was missing" if damage is None else "was damaged ("
        assert len(f.notes) == 1 and f.notes[0].startswith(f"{m} {why}")
        assert f.notes[0].endswith(": rebuilt from 1 intact part")


def test_another_fingerprint_or_a_newer_manifest_is_refused(tmp_path):
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        f.commit("u0", _payload(0))
    with pytest.raises(RunFolderError, match="holds the checkpoints of other work; use another folder"):
        RunFolder(tmp_path, "other", LAYOUT)
    with RunFolder.open(tmp_path, "other", LAYOUT, fresh=True) as f:  # fresh: start over
        assert f.entries == {} and f.session == 1
    (tmp_path / MANIFEST).write_text(json.dumps({"version": 2, "fingerprint": "fp", "sessions": 1, "parts": {}}))
    with pytest.raises(RunFolderError, match="written by a newer jaxplan"):
        RunFolder(tmp_path, "fp", LAYOUT)


def test_discard_removes_the_entry_then_its_files(tmp_path):
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        f.commit("u0", _payload(0))
        f.discard("u0")
        assert not f.done("u0")
    assert not list((tmp_path / "checkpoints" / "parts").iterdir())
    assert not (tmp_path / "checkpoints" / "arrays" / "u0").exists()


def test_a_killed_writers_leftovers_are_removed_on_open(tmp_path):
    RunFolder(tmp_path, "fp", LAYOUT)
    tmp = tmp_path / "checkpoints" / "parts" / ".u0.csv.tmp-1-abcd"
    tmp.write_bytes(b"half")
    orbax_tmp = tmp_path / "checkpoints" / "arrays" / "u0.orbax-checkpoint-tmp-123"
    orbax_tmp.mkdir()
    RunFolder(tmp_path, "fp", LAYOUT)
    assert not tmp.exists() and not orbax_tmp.exists()


def test_the_lock_is_reentrant_in_a_process_and_refuses_another(tmp_path):
    probe = ("import sys\nfrom jaxplan.core.io import folder_lock, FolderInUseError\n"
             f"try:\n    with folder_lock({str(tmp_path)!r}):\n        print('free')\n"
             "except FolderInUseError:\n    print('held')\n")

    def other() -> str:
        return subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip()

    with RunFolder.lock(tmp_path):
        with RunFolder.open(tmp_path, "fp", LAYOUT) as f:  # the tuning loop inside `jaxplan tune` holds it again
            f.commit("u0", _payload(0))
        assert other() == "held"  # the inner block's end did not release the outer one's lock
    assert other() == "free"
    script = (f"import time\nfrom jaxplan.core.run_folder import RunFolder\nwith RunFolder.lock({str(tmp_path)!r}):\n"
              "    print('in', flush=True)\n    time.sleep(30)\n")
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "in"
        with pytest.raises(FolderInUseError, match=f"in use by pid {proc.pid}"):
            with RunFolder.lock(tmp_path):
                pass
    finally:
        proc.kill()
        proc.wait()


def test_a_payload_computed_in_another_process_commits_the_same_bytes(tmp_path):
    """The driver is the only writer: a unit of work returns a picklable payload and the folder's holder commits it;
    the committed entry is the one a local computation gives."""
    import concurrent.futures
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=ctx) as pool:
        remote = list(pool.map(_square, range(3)))
    back = pickle.loads(pickle.dumps(remote[0]))
    assert back.data == remote[0].data and back.info == remote[0].info
    with RunFolder.open(tmp_path / "remote", "fp", LAYOUT) as a, RunFolder.open(tmp_path / "local", "fp", LAYOUT) as b:
        for i, p in enumerate(remote):
            ea, eb = a.commit(f"u{i}", p), b.commit(f"u{i}", _payload(i))
            # the same entry; the array files' digest differs (orbax's metadata holds the time of the save)
            assert {**ea, "arrays_sha256": None} == {**eb, "arrays_sha256": None}
            np.testing.assert_array_equal(a.arrays(f"u{i}")["x"], b.arrays(f"u{i}")["x"])
        assert a.merged(["u0", "u1", "u2"]) == b.merged(["u0", "u1", "u2"])


def test_log_session_keeps_one_record_per_session(tmp_path):
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        f.log_session("sessions.json", {"wall_s": 1.0})
        assert f.log_session("sessions.json", {"wall_s": 2.0}) == [{"wall_s": 2.0}]  # replaced, not appended
    with RunFolder.open(tmp_path, "fp", LAYOUT) as f:
        assert f.log_session("sessions.json", {"wall_s": 3.0}) == [{"wall_s": 2.0}, {"wall_s": 3.0}]
        assert f.log_session("other.json", {"n": 1}, earlier=[{"n": 0}]) == [{"n": 0}, {"n": 1}]
    assert json.loads((tmp_path / "sessions.json").read_text()) == [{"wall_s": 2.0}, {"wall_s": 3.0}]
