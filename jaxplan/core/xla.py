"""`one_thread_options`: XLA compiler options that keep a small CPU program's loops on one thread.

XLA:CPU's ``cpu-parallel-task-assigner`` pass splits every elementwise loop whose estimated cost passes
its threshold across the client's intra-op threads (as many as the cores or host devices). Its cost
model takes a loop over a few hundred samples with a few dozen operations each for 100 µs of work, so a
single robot's control step (800 sampled controls) is split, and on every call from Python the split
loops hand half their work to a thread that has gone to sleep since the last call: waking it costs more
than the half it takes over. A program compiled with these options skips that pass only: the same
kernels, each loop run whole by one thread, give the same bits. The options belong to the one compiled
program (``jax.jit(f, compiler_options=one_thread_options())``); other programs, and XLA_FLAGS, stay as
they are. (XLA:CPU may still run independent kernels of the program on two threads at once: that choice,
made by its thunk executor from the program's dependency graph, has no compiler option.)
"""

from __future__ import annotations

import os
import shlex

__all__ = ["PARALLEL_TASK_PASS", "one_thread_options"]

PARALLEL_TASK_PASS = "cpu-parallel-task-assigner"
"""The name of XLA:CPU's pass that splits loops across intra-op threads (``DebugOptions.xla_disable_hlo_passes``)."""


def _passes_disabled_in_flags(flags: str) -> list[str]:
    """The pass names ``--xla_disable_hlo_passes=a,b`` in an XLA_FLAGS string lists (the last such flag wins)."""
    names: list[str] = []
    try:
        words = shlex.split(flags)
    except ValueError:  # unbalanced quotes: XLA itself would reject the flags; read them as blank-separated
        words = flags.split()
    for word in words:
        if word.startswith("--xla_disable_hlo_passes="):
            names = [n for n in word.split("=", 1)[1].split(",") if n]
    return names


def one_thread_options() -> dict[str, str]:
    """Compiler options for ``jax.jit(..., compiler_options=...)`` that skip XLA:CPU's loop splitting.

    The passes the process already disables through ``XLA_FLAGS`` (``--xla_disable_hlo_passes``) stay
    disabled: the option replaces the flag's list for the program, so the list returned carries them.

    Returns:
      ``{"xla_disable_hlo_passes": "<flags' passes>,cpu-parallel-task-assigner"}``.
    """
    names = _passes_disabled_in_flags(os.environ.get("XLA_FLAGS", ""))
    if PARALLEL_TASK_PASS not in names:
        names.append(PARALLEL_TASK_PASS)
    return {"xla_disable_hlo_passes": ",".join(names)}
