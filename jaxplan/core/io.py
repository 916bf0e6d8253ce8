"""The one atomic write of the library (a reader sees the old file or the new one, never a part of either), the
folder lock of run and tuning folders, and the check that a name taken from a config stays inside its folder.

Every file jaxplan writes for later reading (run folders' trials, checkpoints and manifests, tuning logs,
figures, multi-host shards, saved maps, benchmark JSON) goes through here. The recipe: write a temporary
file in the target's own folder (a rename across file systems would not be atomic), flush it to disk
(``fsync``), rename it over the target (`os.replace`, atomic on POSIX and Windows), then sync the folder so
the rename itself survives a power cut. A process killed at any instant (SIGKILL included) leaves the old
file and, at worst, a temporary file named ``.NAME.tmp-…`` that the next writer may delete.

A run or tuning folder is written by one process at a time: `folder_lock` holds an advisory lock
(``fcntl.flock`` on ``FOLDER/.lock``, which also records the holder's pid) for as long as the process works
there; a second process is refused with `FolderInUseError` ("in use by pid N"). The kernel releases a
``flock`` when its process dies (SIGKILL included), so a lock file left by a dead process is simply taken
over. Where ``fcntl`` is missing (Windows) the lock file is created exclusively and a file naming a pid that
no longer runs is taken over.

Imports nothing from jaxplan (the bottom layer, `jaxplan.core`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
from pathlib import Path
from typing import IO, Iterator

__all__ = ["atomic_write", "atomic_file", "atomic_path", "TMP_GLOB", "LOCK_NAME", "FolderInUseError", "folder_lock",
           "SAFE_NAME", "confined"]

TMP_GLOB = ".*.tmp-*"
"""The glob of the temporary files `atomic_path` leaves behind when its process is killed mid-write."""


def _fsync(path: Path, directory: bool = False) -> None:
    flags = os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0)
    try:
        fd = os.open(path, flags)
    except OSError:  # a folder that cannot be opened (some platforms): the rename is still atomic
        if directory:
            return
        raise
    try:
        os.fsync(fd)
    except OSError:
        if not directory:  # folders on some file systems refuse fsync; files must not
            raise
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; on a clean exit it is synced and renamed to ``path``.

    For writers that want a file name (matplotlib's ``savefig``, Pillow's animation writer): the temporary
    name keeps ``path``'s suffix, so a format chosen by suffix is the same. On an exception the temporary
    file is removed and ``path`` is left as it was. The folder must exist.

    Example::

        with atomic_path("figures/demo.png") as tmp:
            fig.savefig(tmp)
    """
    target = Path(path)
    tmp = target.with_name(f".{target.name}.tmp-{os.getpid()}-{secrets.token_hex(4)}{target.suffix}")
    try:
        yield tmp
        _fsync(tmp)
        os.replace(tmp, target)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        if e.filename is None or str(e.filename) == str(tmp):  # a failed write names no file: name the target
            raise OSError(e.errno, e.strerror or str(e), str(target)) from e
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync(target.parent, directory=True)


@contextlib.contextmanager
def atomic_file(path: str | os.PathLike, mode: str = "wb", encoding: str | None = None) -> Iterator[IO]:
    """An open file that replaces ``path`` atomically when the block ends (``mode`` ``"wb"`` or ``"w"``).

    For writers that take a file object (``json.dump``, ``np.savez``).
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"atomic_file writes a new file: mode must be 'wb' or 'w', got {mode!r}")
    with atomic_path(path) as tmp:
        with open(tmp, mode.replace("w", "x"), encoding=encoding if mode == "w" else None) as f:
            yield f


def atomic_write(path: str | os.PathLike, data: bytes | str, encoding: str = "utf-8") -> Path:
    """Writes ``data`` (bytes, or text encoded with ``encoding``) to ``path`` atomically; returns the path."""
    payload = data.encode(encoding) if isinstance(data, str) else bytes(data)
    with atomic_file(path, "wb") as f:
        f.write(payload)
    return Path(path)


# ---------------------------------------------------------------------------------------------
# Names from configs


SAFE_NAME = r"[A-Za-z0-9][A-Za-z0-9_.-]*"
"""What a file or folder name taken from a config must match (run names, tuning names, figure stems): letters,
digits, ``_ . -``, not starting with a dot or dash — so no separator, no ``..``, no hidden file."""


def confined(folder: str | os.PathLike, name: str, suffix: str = "") -> Path:
    """``folder / (name + suffix)``, refused unless ``name`` is a `SAFE_NAME` and the path stays inside ``folder``.

    Every file name derived from a config goes through here (the config schema checks the same pattern
    first, with the key's path in the message).

    Raises:
      ValueError: naming the offending name.
    """
    if not isinstance(name, str) or not re.fullmatch(SAFE_NAME, name):
        raise ValueError(f"{name!r} cannot name a file: use letters, digits and _ . - (not starting with . or -), "
                         f"so that it stays inside {folder}")
    base = Path(folder)
    path = base / f"{name}{suffix}"
    if os.path.dirname(os.path.normpath(path)) != os.path.normpath(base):  # belt and braces
        raise ValueError(f"{name!r} would write outside {folder}")
    return path


# ---------------------------------------------------------------------------------------------
# One process per folder


LOCK_NAME = ".lock"
"""The lock file of a run or tuning folder (`folder_lock`)."""


class FolderInUseError(RuntimeError):
    """Another live process holds the folder's lock (`folder_lock`); ``pid`` is its process id (0 if unknown)."""

    def __init__(self, folder: Path, pid: int):
        self.folder, self.pid = folder, pid
        who = f"pid {pid}" if pid else "another process"
        super().__init__(f"{folder} is in use by {who} (another jaxplan run or tune writes there); wait for it to "
                         f"finish, or pass another --out")


def _read_pid(path: Path) -> int:
    try:
        return int(path.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 0


def _alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # a process of another user
        return True
    except OSError:
        return False
    return True


@contextlib.contextmanager
def folder_lock(folder: str | os.PathLike) -> Iterator[Path]:
    """Holds ``folder``'s lock for the block: one process at a time writes a run or tuning folder.

    The folder must exist. The lock file ``FOLDER/.lock`` names the holder's pid; it stays behind when
    the block ends (a later process takes it over), and a lock whose process has died is taken over.

    Raises:
      FolderInUseError: another live process holds the lock (its pid in the message).
    """
    path = Path(folder) / LOCK_NAME
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: an exclusive create, a dead holder's file taken over
        fcntl = None
    if fcntl is None:  # pragma: no cover
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
                break
            except FileExistsError:
                pid = _read_pid(path)
                if _alive(pid) and pid != os.getpid():
                    raise FolderInUseError(Path(folder), pid) from None
                path.unlink(missing_ok=True)
        else:
            raise FolderInUseError(Path(folder), _read_pid(path))
        try:
            os.write(fd, f"{os.getpid()}\n".encode())
            os.close(fd)
            yield path
        finally:
            path.unlink(missing_ok=True)
        return
    fd = os.open(path, os.O_CREAT | os.O_RDWR, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            locked = True
        except OSError as e:
            if e.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EACCES):
                raise FolderInUseError(Path(folder), _read_pid(path)) from None
            locked = False  # a file system without flock (ENOLCK, EINVAL): work unlocked rather than not at all
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        try:
            yield path
        finally:
            if locked:
                fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)
