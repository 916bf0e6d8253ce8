"""`PlanResult`: what every global planner returns, and `BatchResult`: what `jaxplan.plan_batch` returns
(docs/guide/planners.md)."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

__all__ = ["BatchResult", "PlanResult"]


class PlanResult(NamedTuple):
    """One planned path.

    Attributes:
      path: ``int64[L, 2]`` cells ``(x, y)`` from start to goal inclusive; ``[0, 2]`` when
        the goal was not reached.
      length: path length in metres (``inf`` when not reached).
      turns: vertices with a heading change (docs/guide/smoothing-and-metrics.md).
      cost: the planner's own objective (for exact planners, the length).
      history: ``f64[iterations]`` best cost after each iteration (empty for exact planners).
      time_s: wall-clock planning time in seconds (excluding one-off compilation where noted).
      success: whether the goal was reached.
      planner: registry name of the planner.
      info: planner-specific extras (for example ``expanded`` nodes).
    """

    path: np.ndarray
    length: float
    turns: int
    cost: float
    history: np.ndarray
    time_s: float
    success: bool
    planner: str
    info: dict[str, Any]

    @staticmethod
    def failure(planner: str, time_s: float, history: np.ndarray | None = None, **info: Any) -> "PlanResult":
        """The result for an unreachable goal: ``success=False``, ``length=cost=inf``."""
        return PlanResult(
            path=np.zeros((0, 2), np.int64),
            length=float("inf"),
            turns=0,
            cost=float("inf"),
            history=np.zeros(0) if history is None else history,
            time_s=time_s,
            success=False,
            planner=planner,
            info=dict(info),
        )

    @staticmethod
    def found(planner: str, path: np.ndarray, length: float, turns: int, time_s: float, *, cost: float | None = None,
              history: np.ndarray | None = None, **info: Any) -> "PlanResult":
        """The result for a reached goal: ``success=True``; ``cost`` is the length unless given (exact planners
        minimise length), ``history`` empty unless given."""
        return PlanResult(
            path=path,
            length=length,
            turns=turns,
            cost=length if cost is None else cost,
            history=np.zeros(0) if history is None else history,
            time_s=time_s,
            success=True,
            planner=planner,
            info=dict(info),
        )

    def to_dict(self) -> dict[str, Any]:
        """Every field as built-in Python (`jaxplan.core.export.plain`): ``path`` a list of ``[x, y]`` cells,
        ``history`` a list, ``info`` a dict of lists and numbers (``inf`` stays a float)."""
        from jaxplan.core.export import plain

        return plain(self._asdict())

    def to_dataframe(self, what: str = "summary") -> Any:
        """A `pandas.DataFrame` (pandas: ``pip install 'jaxplan[export]'``).

        Args:
          what: ``"summary"`` one row (planner, success, length m, cost, turns, cells, time_s);
            ``"path"`` one row per path cell (``step``, ``x``, ``y`` cells); ``"history"`` one row per iteration
            (``iteration`` from 1, ``best_cost``).
        """
        from jaxplan.core.export import check_what, frame

        check_what(what, ("summary", "path", "history"), "PlanResult")
        if what == "path":
            p = np.asarray(self.path).reshape(-1, 2)
            return frame({"step": np.arange(len(p)), "x": p[:, 0], "y": p[:, 1]})
        if what == "history":
            h = np.asarray(self.history)
            return frame({"iteration": np.arange(1, len(h) + 1), "best_cost": h})
        return frame({"planner": [self.planner], "success": [bool(self.success)], "length": [float(self.length)],
                      "cost": [float(self.cost)], "turns": [int(self.turns)], "cells": [len(self.path)],
                      "time_s": [float(self.time_s)]})


class BatchResult(NamedTuple):
    """Stacked results of `plan_batch`, leading axes ``[N scenarios, R seeds]`` (numpy).

    paths ``int64[N, R, P, 2]`` cells, padded with −1 after ``n_cells``; n_cells ``[N, R]``;
    length (m), cost, turns, success, converged ``[N, R]`` (−1 without success);
    history and diversity ``[N, R, I]`` per iteration; successes ``[N, R, I]`` ants at the
    goal per iteration; time_s for the whole call without compilation; compile_s;
    tau ``f32[N, R, S, C, K]`` final pheromone per sub-colony and directed edge (cell
    ``i = y * W + x``, neighbour slot k of `jaxplan.neighbour_table`), only with
    ``keep_pheromone=True`` (else None).
    """

    paths: np.ndarray
    n_cells: np.ndarray
    length: np.ndarray
    cost: np.ndarray
    turns: np.ndarray
    success: np.ndarray
    converged: np.ndarray
    history: np.ndarray
    diversity: np.ndarray
    successes: np.ndarray
    time_s: float
    compile_s: float
    planner: str
    tau: np.ndarray | None = None

    def result(self, i: int, r: int) -> PlanResult:
        """One scenario/seed as a `PlanResult`."""
        n = int(self.n_cells[i, r])
        extra = {} if self.tau is None else {"tau": self.tau[i, r].copy()}
        return PlanResult(
            path=self.paths[i, r, :n].copy(),
            length=float(self.length[i, r]),
            turns=int(self.turns[i, r]),
            cost=float(self.cost[i, r]),
            history=self.history[i, r].copy(),
            time_s=self.time_s / (self.length.shape[0] * self.length.shape[1]),
            success=bool(self.success[i, r]),
            planner=self.planner,
            info={"converged_iteration": int(self.converged[i, r]), "diversity": self.diversity[i, r].copy(),
                  "successes": self.successes[i, r].copy(), "compile_s": self.compile_s, **extra},
        )

    def to_dict(self) -> dict[str, Any]:
        """Every field as built-in Python (`jaxplan.core.export.plain`); ``paths`` as nested lists ``[N][R]`` of
        each run's ``[x, y]`` cells, without the −1 padding (``tau`` only when kept)."""
        from jaxplan.core.export import plain

        d = plain({k: v for k, v in self._asdict().items() if k != "paths" and (k != "tau" or v is not None)})
        d["paths"] = [[self.paths[i, r, : self.n_cells[i, r]].tolist() for r in range(self.paths.shape[1])]
                      for i in range(self.paths.shape[0])]
        return d

    def to_dataframe(self, what: str = "summary") -> Any:
        """A long-form `pandas.DataFrame` (pandas: ``pip install 'jaxplan[export]'``); ``scenario`` and ``seed``
        are indices into the call's scenarios and seeds.

        Args:
          what: ``"summary"`` one row per run (success, length m, cost, turns, cells, converged iteration);
            ``"path"`` one row per path cell (``step``, ``x``, ``y``); ``"history"`` one row per iteration
            (``best_cost``, ``diversity``, ``successes``).
        """
        from jaxplan.core.export import check_what, frame

        check_what(what, ("summary", "path", "history"), "BatchResult")
        N, R = self.length.shape
        sc, se = np.meshgrid(np.arange(N), np.arange(R), indexing="ij")
        if what == "summary":
            return frame({"planner": np.full(N * R, self.planner, object), "scenario": sc.ravel(), "seed": se.ravel(),
                          "success": self.success.ravel(), "length": self.length.ravel(), "cost": self.cost.ravel(),
                          "turns": self.turns.ravel(), "cells": self.n_cells.ravel(),
                          "converged_iteration": self.converged.ravel()})
        if what == "path":
            keep = np.arange(self.paths.shape[2])[None, None, :] < self.n_cells[..., None]  # [N, R, P]
            i, r, k = np.nonzero(keep)
            return frame({"scenario": i, "seed": r, "step": k, "x": self.paths[i, r, k, 0],
                          "y": self.paths[i, r, k, 1]})
        I = self.history.shape[2]
        i, r, k = (a.ravel() for a in np.meshgrid(np.arange(N), np.arange(R), np.arange(I), indexing="ij"))
        return frame({"scenario": i, "seed": r, "iteration": k + 1, "best_cost": self.history.ravel(),
                      "diversity": self.diversity.ravel(), "successes": self.successes.ravel()})
