"""The on-disk compilation caches of jaxplan: JAX's persistent compilation cache and numba's cache, in one folder.

A fresh process otherwise compiles every program again: about 7 s of XLA compilation before a first
``jp.navigate``, and about 30 s of numba for the IACO walk on 2 cores. With the caches, a second process loads
them instead. The folder is ``$JAXPLAN_CACHE``, else ``$XDG_CACHE_HOME/jaxplan``, else ``~/.cache/jaxplan``:
JAX's compiled programs go to ``jax/`` in it, numba's to ``numba/`` (``NUMBA_CACHE_DIR``, unless the user set
that variable). ``JAXPLAN_CACHE=off`` turns jaxplan's caching off (numba then caches where it would on its own,
beside the sources in ``__pycache__``, since jaxplan's kernels ask for ``cache=True``).

The caches are turned on

* on first use, in every ``jaxplan`` command and in the Python API: each module of jaxplan that holds numba
  kernels calls `on_first_use` before its kernels are decorated (numba picks a function's cache folder
  then), and every compiled entry point imports one of them before it compiles anything. ``import jaxplan``
  alone changes nothing (it loads no subpackage), nor does a command that compiles nothing;
* or explicitly by `enable_compilation_cache` (scripts that want another folder call it first). A command's
  ``--no-cache`` calls `disable_compilation_cache` before the command runs.

A cache that cannot be created (a read-only home) is skipped on first use and reported by an explicit call.
`compile_notice` prints one line on a terminal while a long first compilation runs.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from pathlib import Path
from typing import Iterator, Mapping

__all__ = ["ENV", "OFF", "cache_folder", "enable_compilation_cache", "disable_compilation_cache", "on_first_use",
           "compile_notice", "numba_cache_dir"]

ENV = "JAXPLAN_CACHE"
"""The environment variable that moves the cache folder (or turns caching off with `OFF`)."""

OFF = "off"
"""``JAXPLAN_CACHE=off``: no persistent compilation cache."""

MIN_COMPILE_S = 0.0
"""JAX programs that compile faster than this are not written (JAX's default is 1 s): 0, every one. A first
``jp.navigate`` compiles about 60 programs, most of them single operations of 10-50 ms each; loading them
instead cut its XLA time from 2.6 s (only those above 0.2 s kept) to 0.8 s (2026-12-06, 2 busy cores)."""

_UNSET = object()
_state: object = _UNSET  # _UNSET: not decided yet; None: off; a Path: the folder in use
_numba_ours = False  # whether NUMBA_CACHE_DIR was set by this module (then it may move it; never the user's)
_lock = threading.Lock()


def cache_folder(environ: Mapping[str, str] | None = None) -> Path | None:
    """The cache folder named by ``environ`` (default `os.environ`), or None for ``JAXPLAN_CACHE=off``.

    ``$JAXPLAN_CACHE`` (``~`` expanded), else ``$XDG_CACHE_HOME/jaxplan``, else ``~/.cache/jaxplan``. Pure: it
    creates nothing.
    """
    env = os.environ if environ is None else environ
    value = env.get(ENV, "").strip()
    if value.lower() == OFF:
        return None
    if value:
        return Path(value).expanduser()
    xdg = env.get("XDG_CACHE_HOME", "").strip()
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "jaxplan"


def numba_cache_dir() -> Path | None:
    """Where numba writes the kernels decorated from now on (``NUMBA_CACHE_DIR``), or None for numba's default
    (``__pycache__`` beside each source file, or its own user folder when that is read-only)."""
    value = os.environ.get("NUMBA_CACHE_DIR", "")
    return Path(value) if value else None


def _set_numba(folder: Path | None) -> None:
    """Points numba at ``folder`` (None: back to numba's default), unless the user set ``NUMBA_CACHE_DIR``.

    numba reads the variable when it is imported and again on `numba.core.config.reload_config`; a kernel's
    cache folder is fixed when it is decorated, so this moves the kernels decorated afterwards.
    """
    global _numba_ours
    if "NUMBA_CACHE_DIR" in os.environ and not _numba_ours:
        return  # the user's choice stands
    if folder is None:
        os.environ.pop("NUMBA_CACHE_DIR", None)
        _numba_ours = False
    else:
        os.environ["NUMBA_CACHE_DIR"] = str(folder)
        _numba_ours = True
    if "numba.core.config" in sys.modules:
        sys.modules["numba.core.config"].reload_config()


def _set_jax(folder: Path | None, keep_users: bool) -> None:
    """JAX's persistent compilation cache in ``folder`` (None: off) for the compilations from now on.

    ``keep_users``: leave a cache folder the user configured (``JAX_COMPILATION_CACHE_DIR`` or
    ``jax.config``) as it is. JAX opens its cache at the first compilation that uses it; switching folders
    later needs `reset_cache`, which JAX documents for that.
    """
    import jax
    from jax.experimental.compilation_cache import compilation_cache as jcc

    current = jax.config.jax_compilation_cache_dir
    if keep_users and current is not None and _state is _UNSET:
        return
    target = None if folder is None else str(folder)
    if current != target:
        jax.config.update("jax_compilation_cache_dir", target)
        jcc.reset_cache()
    if folder is not None and "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS" not in os.environ:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_S)


def _enable(folder: Path | None, keep_users: bool) -> Path | None:
    global _state
    if folder is None:  # off: undo what an earlier call set up
        if isinstance(_state, Path):
            _set_jax(None, keep_users=False)
            _set_numba(None)
        _state = None
        return None
    folder = folder.resolve()
    if _state == folder:
        return folder
    try:
        (folder / "jax").mkdir(parents=True, exist_ok=True)
        (folder / "numba").mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OSError(f"cannot create the compilation cache folder {folder}: {e.strerror or e}; set {ENV} to a "
                      f"writable folder, or {ENV}={OFF}") from e
    _set_jax(folder / "jax", keep_users)
    _set_numba(folder / "numba")
    _state = folder
    return folder


def enable_compilation_cache(path: str | os.PathLike | None = None) -> Path | None:
    """Turns on jaxplan's on-disk compilation caches (JAX's and numba's); returns the folder used (None: off).

    Compiled programs are written there and a later process loads them instead of compiling again: a
    repeated ``jp.navigate`` in a new process then starts in seconds. jaxplan does this by itself on first use
    and in every command, with the default folder; call this first to choose another. Calling it again with
    the same folder does nothing.

    Args:
      path: the folder (``jax/`` and ``numba/`` are made in it). Default: ``$JAXPLAN_CACHE``, else
        ``$XDG_CACHE_HOME/jaxplan``, else ``~/.cache/jaxplan``; ``JAXPLAN_CACHE=off`` returns None and caches
        nothing.

    numba's folder moves only if ``NUMBA_CACHE_DIR`` is not set by the user, and only for kernels not loaded
    yet (numba fixes a kernel's folder when jaxplan's module holding it is imported).

    Raises:
      OSError: the folder cannot be created (the message names it).
    """
    with _lock:
        return _enable(Path(path).expanduser() if path is not None else cache_folder(), keep_users=path is None)


def disable_compilation_cache() -> None:
    """No on-disk caching by jaxplan from now on in this process (``--no-cache``, ``JAXPLAN_CACHE=off``): JAX's
    persistent cache is turned off and numba goes back to its own default folder, unless the user set one."""
    with _lock:
        _enable(None, keep_users=False)


def on_first_use() -> None:
    """Turns the caches on with the default folder, once per process, unless a command or script decided first
    (`enable_compilation_cache`, `disable_compilation_cache`). A folder that cannot be created leaves the
    caches off (a plan should not fail for want of a cache). Costs a comparison after the first call."""
    global _state
    if _state is not _UNSET:
        return
    with _lock:
        if _state is not _UNSET:
            return
        try:
            _enable(cache_folder(), keep_users=True)
        except OSError:
            _state = None


def _quiet(stream) -> bool:
    """Whether notices stay unprinted: ``stream`` is not a terminal (a pipe, a file, a test's capture), or this
    runs under pytest or CI."""
    if "PYTEST_CURRENT_TEST" in os.environ or os.environ.get("CI"):
        return True
    try:
        return not stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return True


@contextlib.contextmanager
def compile_notice(what: str, expected_s: float, after_s: float = 3.0) -> Iterator[None]:
    """One line on stderr if the block is still running after ``after_s`` seconds and stderr is a terminal:
    ``jaxplan: compiling WHAT (first use, ~EXPECTED s; cached for next time in FOLDER)``.

    A warm start (the block loads a cache in well under ``after_s``) prints nothing; off a terminal nothing
    is started at all. The line goes through `sys.stderr` as it is when printed, so a progress display that
    redirects stderr keeps it above its own line.
    """
    if _quiet(sys.stderr):
        yield
        return
    folder = numba_cache_dir()
    where = f"cached for next time in {folder}" if folder else "cached for next time beside jaxplan's sources"
    line = f"jaxplan: compiling {what} (first use, ~{expected_s:.0f} s; {where})"
    timer = threading.Timer(after_s, lambda: print(line, file=sys.stderr, flush=True))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
