"""Team trials: N robots sharing one episode (`jaxplan.navigate_multi`), li2026 Table 3's multi-robot mode.

A planner with a ``team`` section runs every (scenario, seed) trial as ONE episode of ``team.robots``
robots. Robot 0 takes the scenario's own start and goal, so the team's first robot is the
single-robot trial's; robots 1.. draw theirs per (map, scenario) from ``team.seed`` — not from
the planner or the trial seed, so every planner and seed of a comparison meets the same team —
as the map's random scenarios are drawn (`jaxplan.experiments.prepare.random_pairs`: connected,
at least the map's ``min_distance`` apart, cells ``min_clearance`` from obstacles), keeping every
start and goal ``team.spacing`` m from the teammates' starts and goals.

A trial's row then holds team metrics (li2026 counts over its whole multi-robot run):
success = every robot succeeded; ``arrived`` = the share that did; counts (collisions, contacts,
recoveries, re-plans) and extensive amounts (energy, path length) are summed over the robots;
``time_s`` is the makespan (the last robot's time), ``max_curvature`` the largest of the team's,
``rmse`` the robots' mean. A robot–robot contact is a contact of both robots in ``collisions``
and one contact in ``robot_contacts``.
"""

from __future__ import annotations

import numpy as np

from jaxplan.experiments.config import TeamSpec
from jaxplan.experiments.prepare import MapWork, random_pairs

__all__ = ["team_cells", "team_values", "CANDIDATES"]

_SUMMED = ("collisions", "active_contacts", "passive_contacts", "recoveries", "replans")
_TOTALS = ("energy", "path_length")
_LARGEST = ("time_s", "max_curvature")
_MEAN = ("rmse",)

CANDIDATES = 24
"""Random start-goal pairs drawn per teammate to choose from (those too close to a teammate are skipped)."""


def team_cells(mw: MapWork, m: int, team: TeamSpec, sc: int) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, goals)``, each ``int64[N, 2]`` cells, of scenario ``sc``'s team on map ``m`` (row 0: the scenario).

    Raises:
      ValueError: the map has no room for ``N - 1`` more pairs this far apart.
    """
    N, res = int(team.robots), float(mw.grid.resolution)
    spec = mw.spec.scenarios
    seed = int(np.random.SeedSequence([int(team.seed), int(m), int(sc)]).generate_state(1)[0])
    cand_s, cand_g, _ = random_pairs(mw.grid, CANDIDATES * (N - 1), seed, spec.min_distance, spec.min_clearance)
    starts, goals = [np.asarray(mw.starts[sc], np.int64)], [np.asarray(mw.goals[sc], np.int64)]
    for s, g in zip(cand_s, cand_g, strict=True):
        if len(starts) == N:
            break
        taken = (np.concatenate([starts, goals]) + 0.5) * res  # [2k, 2] m
        new = (np.stack([s, g]) + 0.5) * res
        gap = np.hypot(*(new[:, None] - taken[None]).transpose(2, 0, 1))
        if gap.min() >= team.spacing:
            starts.append(s)
            goals.append(g)
    if len(starts) < N:
        raise ValueError(f"map {mw.spec.name!r}, scenario {sc}: found room for only {len(starts)} of {N} robots with "
                         f"starts and goals {team.spacing:g} m apart; use fewer robots or a smaller team.spacing")
    return np.stack(starts), np.stack(goals)


def team_values(eb, n: int, metrics) -> dict[str, np.ndarray]:
    """Team metric arrays ``[n, R]`` of the first ``n`` scenarios of an `EpisodeBatch` ``[E, R, N]`` (see the
    module docstring); robots that did not run (infeasible) have nan metrics and fail the team."""
    ok = np.asarray(eb.success[:n], bool)  # [n, R, N]
    out: dict[str, np.ndarray] = {"success": np.all(ok, axis=-1).astype(np.int64)}
    pair = np.asarray(eb.pair_collisions[:n], np.int64)  # [n, R, N, N], symmetric
    N = pair.shape[-1]
    upper = np.triu(np.ones((N, N), bool), 1)
    derived = {"arrived": lambda: np.mean(ok, axis=-1),
               "robot_contacts": lambda: np.sum(pair * upper, axis=(-2, -1))}
    for k in metrics:
        if k in derived:
            out[k] = derived[k]()
        elif k in _SUMMED:
            out[k] = np.sum(np.asarray(getattr(eb, k)[:n], np.int64), axis=-1)
        elif k in _TOTALS:
            out[k] = np.sum(np.asarray(getattr(eb, k)[:n], np.float64), axis=-1)  # nan when a robot did not run
        elif k in _LARGEST:
            out[k] = np.max(np.asarray(getattr(eb, k)[:n], np.float64), axis=-1)
        elif k in _MEAN:
            out[k] = np.mean(np.asarray(getattr(eb, k)[:n], np.float64), axis=-1)
    return out
