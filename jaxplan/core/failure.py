"""How the command line ends when something goes wrong: one line naming the cause and what to do, an exit code.

Exit codes (`jaxplan --help` says the same):

* ``2`` — bad input: fix the command, the config or the data (a config problem, a malformed file, a batch
  that asks for more memory than the limit, a run folder of another experiment, a bad environment variable);
* ``1`` — a fault of the environment: retrying may work once it is fixed (a read-only or full disk, the
  machine out of memory, a damaged checkpoint, XLA out of resources, a folder in use by another process,
  a Ray cluster that cannot be reached, or a bug: any other exception);
* ``130`` — interrupted (Ctrl-C): everything committed so far is kept; the same command resumes;
* ``143`` — terminated (SIGTERM: how Slurm, Kubernetes and ``kill`` stop a job): the same as Ctrl-C.

The traceback is printed only with ``jaxplan --debug``. Only the standard library is imported here
(``jaxplan --help`` answers without JAX): the library's own exception classes are looked up in
`sys.modules`, where they are whenever one of them was raised.
"""

from __future__ import annotations

import errno
import sys

__all__ = ["BAD_INPUT", "FAULT", "INTERRUPTED", "TERMINATED", "Terminated", "describe_failure", "interrupted_line"]

BAD_INPUT = 2
FAULT = 1
INTERRUPTED = 130
TERMINATED = 143
"""128 + SIGTERM, the status a shell reports for a process the signal killed."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread as Ctrl-C's `KeyboardInterrupt` is, so that a command stops the same way
    (finished work committed, the rest left for the same command to resume)."""


_RESUMABLE = ("run", "tune", "reproduce", "study")
_FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)
_DENIED = (errno.EACCES, errno.EPERM, errno.EROFS)


def _loaded(module: str, name: str) -> type | None:
    """Class ``name`` of ``module`` if that module is loaded (an instance can only exist if it is)."""
    mod = sys.modules.get(module)
    return getattr(mod, name, None) if mod is not None else None


def _is(e: BaseException, module: str, name: str) -> bool:
    cls = _loaded(module, name)
    return cls is not None and isinstance(e, cls)


def _first_line(text: object, limit: int = 300) -> str:
    line = next((x.strip() for x in str(text).splitlines() if x.strip()), "")
    return line if len(line) <= limit else line[: limit - 1] + "…"


def interrupted_line(command: str | None, terminated: bool = False) -> str:
    """The line printed after Ctrl-C (after SIGTERM with ``terminated``)."""
    what, code = ("terminated (SIGTERM)", TERMINATED) if terminated else ("interrupted", INTERRUPTED)
    if command in _RESUMABLE:
        return f"jaxplan: {what}; everything finished so far is saved: run the same command to resume (exit {code})"
    return f"jaxplan: {what} (exit {code})"


def _os_error(e: OSError, command: str | None) -> str:
    path = e.filename if e.filename is not None else "a file"
    what = e.strerror or type(e).__name__
    resume = " then run the same command to resume" if command in _RESUMABLE else " then run the command again"
    if e.errno in _FULL:
        return (f"cannot write {path}: {what} (the disk is full or a file size limit is reached); free some space,"
                f"{resume} (nothing already saved is lost)")
    if e.errno in _DENIED:
        return (f"cannot write {path}: {what} (the folder is read-only or not yours); pass a writable --out "
                f"folder or fix its permissions")
    return f"{path}: {what}; check that the path exists and is usable,{resume}"


def describe_failure(e: BaseException, command: str | None = None) -> tuple[int, str]:
    """``(exit code, message)`` of exception ``e`` raised by ``jaxplan COMMAND`` (the message without the
    ``jaxplan: error:`` prefix; one line except a config's list of problems)."""
    if isinstance(e, Terminated):
        return TERMINATED, interrupted_line(command, terminated=True)
    if isinstance(e, KeyboardInterrupt):
        return INTERRUPTED, interrupted_line(command)
    if _is(e, "jaxplan.core.executor", "ClusterUnreachable"):
        return FAULT, _first_line(e, 1000)
    if _is(e, "jaxplan.experiments.schema", "ConfigError"):
        return BAD_INPUT, f"invalid config {e}"
    if _is(e, "jaxplan.core.io", "FolderInUseError"):
        return FAULT, str(e)
    if _is(e, "jaxplan.experiments.store", "CheckpointError"):
        return FAULT, _first_line(e, 1000)
    if _is(e, "jaxplan.scale._memory", "MemoryLimitError"):
        return BAD_INPUT, _first_line(e, 1000)
    if isinstance(e, MemoryError):
        return FAULT, ("out of memory: the machine could not give the memory this step needed; use fewer seeds, "
                       "scenarios or ants per chunk (--chunk), or set JAXPLAN_MEMORY_LIMIT so that the memory guard "
                       "refuses such a batch before it starts")
    if isinstance(e, FileNotFoundError):
        return BAD_INPUT, _first_line(e, 1000)
    if isinstance(e, OSError):
        return FAULT, _os_error(e, command)
    if isinstance(e, ValueError):
        return BAD_INPUT, _first_line(e, 1000) if "\n" not in str(e).strip() else str(e).strip()
    name = type(e).__name__
    text = _first_line(e)
    if name in ("XlaRuntimeError", "JaxRuntimeError") or "RESOURCE_EXHAUSTED" in text:
        if "RESOURCE_EXHAUSTED" in text or "out of memory" in text.lower():
            return FAULT, (f"XLA ran out of memory ({text}); use fewer seeds, scenarios or ants per chunk, or set "
                           f"JAXPLAN_MEMORY_LIMIT so that the memory guard refuses such a batch before it starts")
        return FAULT, f"XLA failed: {text} (run with --debug for the traceback)"
    if type(e).__module__.split(".")[0] in ("orbax", "tensorstore"):
        return FAULT, f"checkpoint error: {text}; the run's checkpoints may be damaged (run with --debug for details)"
    return FAULT, f"internal error: {name}: {text} (run with --debug for the traceback, and please report it)"
