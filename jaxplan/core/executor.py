"""Where independent work units run: in this process, or as Ray tasks on a cluster.

A run (`jaxplan run`, `reproduce`, `study`) is a list of independent units — an experiment chunk, one
(method, tuner seed) run of a study — and one driver that commits each unit's result to the run folder. An
executor only decides where the units are computed::

    ex = executor_from("auto")            # or None (this process), "HOST:PORT", or an Executor
    for i, result, where in ex.run(fn, shared, items):
        commit(items[i], result, where)   # the driver is the only writer

``fn(shared, item)`` must be a module-level function (Ray ships it by reference: every node has jaxplan
installed) that returns plain data (rows, arrays, timings); ``shared`` is sent to the cluster once (Ray's
object store), so maps and scenarios travel with the work and workers need no shared file system. Results
come back in the order units finish; a driver that needs a fixed order (``trials.csv``) orders them itself.

Faults (`RayExecutor`): a worker process or node that dies mid-task has its task retried on another worker
(``max_retries``); an exception raised by ``fn`` itself (bad input: a ``ValueError``) is not retried and is
re-raised on the driver as the same exception, as a local run would raise it. A cluster that cannot be reached
raises `ClusterUnreachable` within ``connect_timeout`` seconds (Ray's own connection attempt retries for
minutes).

Ray is imported only by `RayExecutor` (the optional extra ``jaxplan[ray]``): ``import jaxplan`` and every
command without ``--ray`` never import it.
"""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import socket
import threading
from collections.abc import Callable, Generator, Iterator, Sequence
from typing import Any, NamedTuple, Protocol, TypeVar

__all__ = ["ClusterUnreachable", "Executor", "Finished", "LocalExecutor", "Placement", "RayExecutor", "executor_from"]

S = TypeVar("S")
T = TypeVar("T")
R = TypeVar("R")


class ClusterUnreachable(ConnectionError):
    """The Ray cluster at the given address cannot be reached (or Ray is not installed)."""


class Placement(NamedTuple):
    """Where one unit ran: the node's id (Ray's, or ``local``), its host name and the worker's process id."""

    node: str
    host: str
    pid: int


Finished = Generator[tuple[int, R, Placement], None, None]
"""What `Executor.run` yields: ``(index of the unit, its result, where it ran)`` as units finish (a generator: closing
it stops the units not yet finished)."""


class Executor(Protocol):
    """Runs ``fn(shared, item)`` for every item; yields ``(index, result, placement)`` as units finish."""

    kind: str

    def run(self, fn: Callable[[S, T], R], shared: S, items: Sequence[T]) -> Finished[R]:
        ...

    def cluster(self) -> dict[str, Any]:
        """The machines the units run on, for ``meta.json``: kind, address, nodes with their CPUs."""
        ...

    def close(self) -> None:
        ...


def _here() -> Placement:
    return Placement("local", socket.gethostname(), os.getpid())


class LocalExecutor:
    """Every unit in this process, one after the other, in the order given (today's behaviour)."""

    kind = "local"

    def run(self, fn: Callable[[S, T], R], shared: S, items: Sequence[T]) -> Finished[R]:
        where = _here()
        for i, item in enumerate(items):
            yield i, fn(shared, item), where

    def cluster(self) -> dict[str, Any]:
        return {"kind": "local", "nodes": [{"host": socket.gethostname(), "cpus": os.cpu_count()}]}

    def close(self) -> None:
        pass


def _reachable(address: str, timeout: float) -> str | None:
    """None if a TCP connection to ``HOST:PORT`` opens within ``timeout`` s, else why not."""
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit():
        return f"{address!r} is not HOST:PORT (or 'auto')"
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            return None
    except OSError as e:
        return f"no Ray cluster answers at {address} ({e.strerror or e})"


def _started_cluster() -> str | None:
    """The cluster ``auto`` joins: ``$RAY_ADDRESS``, else the one ``ray start --head`` last started on this machine
    (Ray's record of it), else None. Ray's own ``auto`` would also join a Ray instance that another command started
    for itself, and that instance ends with that command."""
    if os.environ.get("RAY_ADDRESS"):
        return os.environ["RAY_ADDRESS"]
    try:
        from ray._private.services import find_bootstrap_address
    except ImportError:  # another Ray layout: Ray's own rule
        return "auto"
    return find_bootstrap_address(None)


@contextlib.contextmanager
def _signals_kept() -> Iterator[None]:
    """The process's SIGINT and SIGTERM handlers as they were before the block: ``ray.init`` replaces SIGTERM's
    with one that calls ``sys.exit``, and ``ray.shutdown`` of a cluster started here resets the signals to their
    defaults underneath Python (a later SIGTERM then kills the process though `signal.getsignal` still names the
    handler); ``jaxplan`` stops on SIGTERM as on Ctrl-C (exit 143, finished work committed)."""
    main = threading.current_thread() is threading.main_thread()
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)} if main else {}
    try:
        yield
    finally:
        for sig, handler in before.items():
            if handler is not None:
                signal.signal(sig, handler)


def _ray_call(fn: Callable[[S, T], R], shared: S, item: T) -> tuple[R, Placement]:
    """The Ray task: ``fn(shared, item)`` and where it ran (the worker's JAX and numba caches turn on by
    themselves on first use, in the node's own ``~/.cache/jaxplan``)."""
    import ray

    node = ray.get_runtime_context().get_node_id()
    return fn(shared, item), Placement(node, socket.gethostname(), os.getpid())


class RayExecutor:
    """Every unit a Ray task (one CPU each); results are yielded as tasks finish.

    Args:
      address: ``"auto"`` joins ``$RAY_ADDRESS`` or the cluster ``ray start --head`` started on this machine or,
        if there is none, starts one with this machine's cores for this executor alone (shut down by `close`);
        ``"HOST:PORT"`` joins that cluster's head (its GCS port, 6379 by default).
      max_retries: how often a task whose worker died is run again elsewhere.
      cpus_per_task: CPUs Ray reserves for each task (a JAX chunk keeps one core busy; more on a GPU node is
        the user's call).
      connect_timeout: seconds to wait for ``HOST:PORT`` to answer before `ClusterUnreachable`.
      num_cpus: with ``"auto"`` and no cluster running: the local cluster's CPUs (default: all cores).

    Raises:
      ClusterUnreachable: Ray is not installed, or the address does not answer.
    """

    kind = "ray"

    def __init__(self, address: str = "auto", *, max_retries: int = 3, cpus_per_task: float = 1.0,
                 connect_timeout: float = 5.0, num_cpus: int | None = None):
        try:
            import ray
        except ImportError as e:
            raise ClusterUnreachable("--ray needs Ray: pip install 'jaxplan[ray]'") from e
        self.address = address
        self.max_retries = max_retries
        self.cpus_per_task = cpus_per_task
        self._started = False
        if not ray.is_initialized():
            with _signals_kept():
                self._init(ray, address, connect_timeout, num_cpus)

    def _init(self, ray: Any, address: str, connect_timeout: float, num_cpus: int | None) -> None:
        if address == "auto":
            if _started_cluster() is not None:
                try:
                    ray.init(address="auto", logging_level="ERROR", log_to_driver=False)
                    return
                except ConnectionError:  # a stale record of a cluster that has stopped
                    pass
            # None running: one for this command alone ("local": never another command's, which could end first)
            ray.init(address="local", num_cpus=num_cpus, logging_level="ERROR", log_to_driver=False,
                     include_dashboard=False)
            self._started = True
        else:
            why = _reachable(address, connect_timeout)
            if why is not None:
                raise ClusterUnreachable(f"{why}; start it there (ray start --head) or check --ray")
            try:
                ray.init(address=address, logging_level="ERROR", log_to_driver=False)
            except (ConnectionError, RuntimeError) as e:
                first = next((x for x in str(e).splitlines() if x.strip()), type(e).__name__)
                raise ClusterUnreachable(f"cannot join the Ray cluster at {address}: {first}") from e

    @functools.cached_property
    def _task(self) -> Any:
        import ray

        # retry_exceptions=False: only a dead worker is retried; an exception of fn (bad input) ends the run
        return ray.remote(num_cpus=self.cpus_per_task, max_retries=self.max_retries,
                          retry_exceptions=False)(_ray_call)

    def run(self, fn: Callable[[S, T], R], shared: S, items: Sequence[T]) -> Finished[R]:
        import ray

        if not items:
            return
        ref = ray.put(shared)
        pending = {self._task.remote(fn, ref, item): i for i, item in enumerate(items)}
        try:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1)
                for r in ready:
                    i = pending.pop(r)
                    try:
                        result, where = ray.get(r)
                    except ray.exceptions.RayTaskError as e:
                        cause = getattr(e, "cause", None)  # the task's own exception, raised as locally
                        raise (cause if isinstance(cause, BaseException) else e.as_instanceof_cause()) from None
                    yield i, result, where
        finally:
            for r in pending:  # interrupted, or a task failed: the rest is not wanted
                ray.cancel(r, force=True)

    def cluster(self) -> dict[str, Any]:
        import ray

        nodes = [{"node": n["NodeID"], "host": n.get("NodeManagerHostname") or n["NodeManagerAddress"],
                  "address": n["NodeManagerAddress"], "cpus": n["Resources"].get("CPU", 0.0)}
                 for n in ray.nodes() if n.get("Alive")]
        return {"kind": "ray", "address": self.address, "started_here": self._started, "nodes": nodes}

    def close(self) -> None:
        import ray

        if self._started:
            with _signals_kept():
                ray.shutdown()


def executor_from(spec: str | Executor | None) -> Executor:
    """The executor for a ``--ray`` value: None → `LocalExecutor`; ``"auto"`` or ``"HOST:PORT"`` →
    `RayExecutor`; an executor is returned as it is."""
    if spec is None:
        return LocalExecutor()
    if isinstance(spec, str):
        return RayExecutor(spec)
    return spec
