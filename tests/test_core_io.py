"""The one atomic write (`jaxplan.core.io`): bytes and text, old file kept on failure, no temporary left."""

from __future__ import annotations

import json
import os
import stat

import pytest

from jaxplan.core.io import TMP_GLOB, atomic_file, atomic_path, atomic_write


def test_atomic_write_bytes_and_text(tmp_path):
    p = tmp_path / "a.csv"
    assert atomic_write(p, b"x,y\n1,2\n") == p
    assert p.read_bytes() == b"x,y\n1,2\n"
    atomic_write(p, "mean ± sd\n")
    assert p.read_bytes() == "mean ± sd\n".encode()
    atomic_write(p, "abc", encoding="ascii")
    assert p.read_text() == "abc"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.csv"]
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~umask  # as open() would create it, not mkstemp's 0600


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    p = tmp_path / "fig.png"
    p.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with atomic_path(p) as tmp:
            assert tmp.parent == tmp_path and tmp.suffix == ".png"  # a format chosen by suffix stays the same
            tmp.write_bytes(b"half")
            raise RuntimeError("killed")
    assert p.read_bytes() == b"old"
    assert not list(tmp_path.glob(TMP_GLOB))


def test_atomic_file_for_writers_that_take_a_file(tmp_path):
    p = tmp_path / "d.json"
    with atomic_file(p, "w") as f:
        json.dump({"a": 1}, f)
        assert not p.exists()  # nothing visible before the block ends
    assert json.loads(p.read_text()) == {"a": 1}
    with pytest.raises(ValueError, match="mode"):
        with atomic_file(p, "a"):
            pass


def test_folder_lock_refuses_a_second_process_and_takes_over_a_dead_ones(tmp_path):
    import subprocess
    import sys

    from jaxplan.core.io import LOCK_NAME, FolderInUseError, folder_lock

    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\nfrom jaxplan.core.io import folder_lock\n"
                               f"with folder_lock({str(tmp_path)!r}):\n    print('held', flush=True)\n"
                               "    time.sleep(60)\n"], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(FolderInUseError, match=f"in use by pid {holder.pid}") as e:
            with folder_lock(tmp_path):
                pass
        assert e.value.pid == holder.pid
    finally:
        holder.kill()
        holder.wait()
    # The kernel dropped the dead holder's lock: it is taken over, and the file names the new holder.
    assert (tmp_path / LOCK_NAME).read_text().split()[0] == str(holder.pid)
    with folder_lock(tmp_path) as path:
        assert path.read_text().split()[0] == str(os.getpid())
    with folder_lock(tmp_path):  # released at the end of the block
        pass


def test_confined_names_stay_inside_their_folder(tmp_path):
    from jaxplan.core.io import confined

    assert confined(tmp_path, "run-1.quick", ".png") == tmp_path / "run-1.quick.png"
    for bad in ("..", "../x", "a/b", "a\\b", ".hidden", "-rf", "", "x\ny", None):
        with pytest.raises(ValueError, match="cannot name a file"):
            confined(tmp_path, bad)
