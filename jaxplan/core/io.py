"""The one atomic write of the library: a reader sees the old file or the new one, never a part of either.

Every file jaxplan writes for later reading (run folders' trials, checkpoints and manifests, tuning logs,
figures, multi-host shards, saved maps, benchmark JSON) goes through here. The recipe: write a temporary
file in the target's own folder (a rename across file systems would not be atomic), flush it to disk
(``fsync``), rename it over the target (`os.replace`, atomic on POSIX and Windows), then sync the folder so
the rename itself survives a power cut. A process killed at any instant (SIGKILL included) leaves the old
file and, at worst, a temporary file named ``.NAME.tmp-…`` that the next writer may delete.

Imports nothing from jaxplan (the bottom layer, `jaxplan.core`).
"""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path
from typing import IO, Iterator

__all__ = ["atomic_write", "atomic_file", "atomic_path", "TMP_GLOB"]

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
