"""`PlanResult`: what every global planner returns (docs/guide/planners.md)."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

__all__ = ["PlanResult"]


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
