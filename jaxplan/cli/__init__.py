"""Command line: ``jaxplan demo | plan | navigate | run | figures | export | reproduce | tune | study | bench``.

``jaxplan --help`` and every ``jaxplan CMD --help`` answer without importing JAX or numba: this
package imports only the standard library at the top, and each command imports what it needs.
Before a command runs, the process opts in to one JAX CPU host device per core
(`jaxplan.use_host_devices`; ``$JAXPLAN_HOST_DEVICES`` overrides the count, ``off`` leaves JAX's
default, and an ``XLA_FLAGS`` device count stands), so batched calls shard over the cores. Compiled programs
are kept on disk and loaded by the next command (`jaxplan.core.compile_cache`: ``$JAXPLAN_CACHE`` or
``~/.cache/jaxplan``); every command's ``--no-cache``, or ``JAXPLAN_CACHE=off``, turns that off.

Long commands (``run``, ``reproduce``, ``tune``, ``figures``, ``demo``, ``bench``, ``plan``, ``navigate``) draw a
progress bar with the time left (or a spinner for a stage such as compiling) on stderr when it is a terminal;
``--no-progress`` turns it off, and piped output never has one (`jaxplan.core.progress`).

A failure ends in one line naming the cause and what to do, with exit code 2 (bad input) or 1 (a fault of
the environment); Ctrl-C ends with 130 and says how to resume, and SIGTERM (how Slurm and Kubernetes preempt a
job) stops a command the same way with 143; ``jaxplan --debug CMD`` adds the traceback (`jaxplan.core.failure`).

Modules: `jaxplan.cli.parser` (the commands and their options), `jaxplan.cli.commands` (one ``cmd_*`` function
per command), `jaxplan.cli.args` (arguments into library values), and what the commands print and write:
`jaxplan.cli.tables` (the terminal tables), `jaxplan.cli.outputs` (``plan --out`` and ``navigate --out`` files) and
`jaxplan.cli.demo` (``jaxplan demo``). ``python -m jaxplan.cli`` is the ``jaxplan`` script.
"""

from __future__ import annotations

import sys
from typing import Any, Sequence

from jaxplan.cli.commands import cmd_bench
from jaxplan.cli.parser import build_parser

__all__ = ["main", "build_parser"]


def _use_host_devices() -> None:
    """One JAX CPU host device per core for this process (`jaxplan.use_host_devices`), unless JAX already runs
    here: `main` called from a Python process that has computed with JAX keeps that process's devices."""
    from jaxplan.scale import use_host_devices

    try:
        use_host_devices()
    except RuntimeError:
        pass


def _caught(signum: int) -> bool:
    """Whether this process still catches signal ``signum`` (Linux: ``/proc/self/status``; True where that cannot
    be read). A library may reset a signal to its default underneath Python (``ray.shutdown`` does, until
    `jaxplan.core.executor` restores the handler): a repeat sent then would kill the process without its message."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    except (OSError, ValueError):
        pass
    return True


class _Interrupts:
    """Ctrl-C or SIGTERM during a command: the signal raises `KeyboardInterrupt` (SIGTERM its subclass
    `jaxplan.core.failure.Terminated`) in the main thread, so finished work stays committed and the command ends
    as it does on Ctrl-C; after the first one the same signal is sent again every half second until the command
    has stopped: an interrupt raised while Python runs a garbage-collection callback (JAX registers one) is
    swallowed there, and the command would go on for hours. Those swallowed ones are not reported either (no
    "Exception ignored" traceback)."""

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self):
        import threading

        self.hit: int | None = None  # the signal that stops the command
        self.stopped = threading.Event()
        self.repeater: threading.Thread | None = None
        self.previous: dict[int, Any] = {}
        self.hook = sys.unraisablehook

    def __enter__(self) -> "_Interrupts":
        import signal
        import threading

        from jaxplan.core.failure import Terminated

        self.terminated = Terminated
        if threading.current_thread() is threading.main_thread():
            for name in self.SIGNALS:
                sig = getattr(signal, name)
                self.previous[sig] = signal.signal(sig, self._handler)
        return self

    def _handler(self, signum: int, frame: Any) -> None:
        import signal

        if self.hit is None:
            import threading

            self.hit = signum
            hook = self.hook
            sys.unraisablehook = lambda u: None if isinstance(u.exc_value, KeyboardInterrupt) else hook(u)
            self.repeater = threading.Thread(target=self._repeat, daemon=True)
            self.repeater.start()
        raise self.terminated() if self.hit == signal.SIGTERM else KeyboardInterrupt

    def _repeat(self) -> None:
        import os

        hit = self.hit
        while hit is not None and not self.stopped.wait(0.5):
            if _caught(hit):
                os.kill(os.getpid(), hit)

    def __exit__(self, *exc: object) -> None:
        import signal

        self.stopped.set()
        for sig, previous in self.previous.items():  # after a stop, a repeat still on its way is ignored
            signal.signal(sig, signal.SIG_IGN if self.hit is not None else previous)
        if self.repeater is not None:  # and none comes later (it could find SIGTERM's default: death)
            self.repeater.join()

    def restore(self) -> None:
        """The signal handlers and unraisable hook as they were before the command."""
        import signal

        sys.unraisablehook = self.hook
        for sig, previous in self.previous.items():
            signal.signal(sig, previous)


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``jaxplan ARGV``; returns the exit status: 0 done, 2 bad input, 1 a fault, 130 interrupted, 143
    terminated (SIGTERM).

    A failure prints one line on stderr naming the cause and what to do (`jaxplan.core.failure`), and the
    traceback only with ``--debug``. Called as the console script (``argv`` None), an interrupted process
    leaves at once after its message (``os._exit``): JAX's and numba's threads are not waited for.
    """
    args = build_parser().parse_args(argv)
    interrupts = _Interrupts()
    try:
        with interrupts:
            if args.func is not cmd_bench:  # the benchmarks run in a process of their own, which opts in itself
                _use_host_devices()
            if getattr(args, "no_cache", False):  # else the caches turn on when compiled code first loads
                from jaxplan.core.compile_cache import disable_compilation_cache

                disable_compilation_cache()
            return int(args.func(args))
    except (Exception, KeyboardInterrupt) as e:  # noqa: BLE001 - every failure ends in one line and an exit code
        import signal

        from jaxplan.core.failure import INTERRUPTED, TERMINATED, Terminated, describe_failure

        if args.debug:
            import traceback

            traceback.print_exc()
        if isinstance(e, KeyboardInterrupt) and interrupts.hit == signal.SIGTERM:
            e = Terminated()  # whatever re-raised it on the way
        code, message = describe_failure(e, args.command)
        stopped = code in (INTERRUPTED, TERMINATED)
        print(message if stopped else f"jaxplan: error: {message}", file=sys.stderr, flush=True)
        if stopped and argv is None:
            import os

            sys.stdout.flush()
            os._exit(code)
        return code
    finally:
        interrupts.restore()

