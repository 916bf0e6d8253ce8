"""Episodes run to their ends for their outcomes alone, finished groups dropped as they finish.

`run_episodes` is one compiled loop over the whole batch: it steps every episode until the slowest
ends, so a batch whose episodes mostly end early pays for the slowest one B times over. Tuning on
navigation episodes (`jaxplan.tune.nav_objective`) needs only how each episode ended, and its batches
are like that: among walkers, half of the episodes of a study's batch end within a third of the time
limit, and one deadlock keeps the loop going to the limit (measured: docs/decisions.md, "Tuning on
navigation episodes").

`run_outcomes` drives the same steps from the host instead: `run_chunk` (`NavConfig.chunk` steps of
`run_episodes`' loop, trajectories dropped) on the batch, then the finished episodes' outcomes are
read, and once the unfinished re-planning groups fit in half the batch (or a quarter, …) they are
gathered into a batch of that size and the rest is dropped. Whole groups move together, in order,
because a group's episodes share re-planning slots (`jaxplan.nav._replan.replan_slots`) and nothing
else couples two episodes: an episode's steps are those `run_episodes` runs for it (tested bit for
bit). A batch size compiles once per (config, shapes); sizes halve, so a batch of ``g`` groups
compiles at most ``1 + ceil(log2 g)`` programs, kept in the caller's ``programs`` dict.
"""

from __future__ import annotations

import math
import time
from typing import Any, MutableMapping, NamedTuple

import jax
import numpy as np

from jaxplan.dwa import ClearanceTable, DWAParams
from jaxplan.mppi import MPPIParams
from jaxplan.nav._config import NavConfig
from jaxplan.nav._episode import initial_carry, run_chunk
from jaxplan.nav._replan import group_size
from jaxplan.nav._state import Carry, EpisodeInputs

__all__ = ["EpisodeOutcomes", "run_outcomes"]


class EpisodeOutcomes(NamedTuple):
    """How each episode of a `run_outcomes` call ended (numpy, ``[B, N]`` = episodes, robots): the fields of
    `EpisodeOutput` with the same names and meaning.

    Attributes:
      steps, reason, collisions, active_contacts, replans: ``int32[B, N]``.
      stepped: episode-steps computed (each chunk's batch size × `NavConfig.chunk`, summed): the work done.
      compile_s: seconds spent compiling programs this call.
    """

    steps: np.ndarray
    reason: np.ndarray
    collisions: np.ndarray
    active_contacts: np.ndarray
    replans: np.ndarray
    stepped: int
    compile_s: float


_INITIAL = jax.jit(initial_carry, static_argnums=0)


def _take(tree: Any, rows: np.ndarray) -> Any:
    """Every leaf's rows ``rows`` along its leading (episode) axis."""
    idx = jax.numpy.asarray(rows)
    return jax.tree_util.tree_map(lambda a: a[idx], tree)


def _take_carry(c: Carry, rows: np.ndarray) -> Carry:
    t = c.t
    return _take(c._replace(t=None), rows)._replace(t=t)


def _rows(groups: np.ndarray, G: int) -> np.ndarray:
    """The episode rows of ``groups`` (group numbers), in order."""
    return (groups[:, None] * G + np.arange(G)).reshape(-1)


def run_outcomes(config: NavConfig, steps: int, table: ClearanceTable, free: jax.Array,
                 params: DWAParams | MPPIParams, inputs: EpisodeInputs, per_episode: bool = False,
                 programs: MutableMapping | None = None) -> EpisodeOutcomes:
    """Runs ``B`` episodes to their ends and returns how they ended, dropping finished groups (module docstring).

    Args: as `run_episodes` (``steps`` a multiple of ``config.chunk``); ``programs``: a dict the caller keeps
      to reuse compiled programs across calls (keyed by batch size, config and shapes); None compiles afresh.

    Returns:
      `EpisodeOutcomes`: equal to the same fields of ``run_episodes(config, steps, table, free, params,
      inputs, per_episode)``.
    """
    B, N = inputs.start.shape[:2]
    G = group_size(config, B)
    n_groups = -(-B // G)
    if n_groups * G > B:  # a partial last group: padded with episodes that do not run (as replan_slots pads it)
        pad = np.minimum(np.arange(n_groups * G), B - 1)
        inputs = _take(inputs, pad)
        inputs = inputs._replace(active=inputs.active.at[B:].set(False))
        if per_episode:
            params = _take(params, pad)
    programs = {} if programs is None else programs
    compile_s = 0.0

    def program(c: Carry, p: Any, x: EpisodeInputs):
        nonlocal compile_s
        args = (c, p, x, table, free)
        key = (config, per_episode, jax.tree_util.tree_structure(args),
               tuple((a.shape, a.dtype) for a in jax.tree_util.tree_leaves(args)))
        if key not in programs:
            t0 = time.perf_counter()
            fn = lambda cc, pp, xx, tt, ff: run_chunk(config, tt, ff, pp, xx, cc, per_episode)  # noqa: E731
            programs[key] = jax.jit(fn).lower(c, p, x, table, free).compile()
            compile_s += time.perf_counter() - t0
        return programs[key](c, p, x, table, free)

    fields = ("steps", "reason", "collisions", "active_contacts", "replans")
    out = {f: np.zeros((n_groups * G, N), np.int32) for f in fields}
    live = np.arange(n_groups)  # the original group held in each group slot of the batch (-1: a finished copy)
    c = _INITIAL(config, inputs)
    p = params
    stepped, k = 0, 0
    while k * config.chunk < steps:
        c = program(c, p, inputs)
        k += 1
        stepped += live.size * G * config.chunk
        done = np.asarray(c.done).reshape(live.size, G * N).all(axis=1)
        rows, got = _rows(live[live >= 0], G), _rows(np.nonzero(live >= 0)[0], G)
        vals = jax.device_get({f: getattr(c, f) for f in fields})
        for f in fields:
            out[f][rows] = vals[f][got]
        running = np.nonzero(~done & (live >= 0))[0]
        if running.size == 0:
            break
        size = live.size
        while size > 1 and running.size <= math.ceil(size / 2):
            size = math.ceil(size / 2)
        if size < live.size:
            # the running groups first, then copies of a finished one (it stays finished: no work, no output)
            spare = np.nonzero(done | (live < 0))[0][0]
            keep = np.concatenate([running, np.full(size - running.size, spare)])
            sel = _rows(keep, G)
            c, inputs = _take_carry(c, sel), _take(inputs, sel)
            if per_episode:
                p = _take(p, sel)
            live = np.where(np.arange(size) < running.size, live[keep], -1)
    return EpisodeOutcomes(**{f: v[:B] for f, v in out.items()}, stepped=stepped, compile_s=compile_s)
