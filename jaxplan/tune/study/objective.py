"""The study's objective: each map's objective (train and held-out splits disjoint, checked) joined over the maps,
and a wrapper that counts the training evaluations a strategy spends.

Budget: the objective is wrapped (`CountedObjective`) so that every weight vector a strategy has evaluated on the
training split is counted; a run whose count differs from ``budget`` is an error, and every method's count is in
the log. The gradient routes that apply to a black-box planner (``reinforce``: a score-function gradient;
``surrogate``: a quadratic model) spend exactly their population's forward evaluations per step, so one step
costs ``population`` evaluations; a differentiable objective (relaxed DWA) would be charged its forward
evaluations too (the backward pass is not counted as an evaluation).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from jaxplan.tune._composite import aco_own_objective, check_disjoint, concat_objectives
from jaxplan.tune._objective import Evaluation, Objective
from jaxplan.tune._workflow import build_objective, split_scenarios
from jaxplan.tune.study.config import StudyConfig

__all__ = ["CountedObjective", "build_study_objective"]


class CountedObjective:
    """An `Objective` whose training-split evaluations are counted (rows of every population evaluated).

    Everything else is the wrapped objective's; ``count`` is the number of weight vectors evaluated on ``"train"``
    through this wrapper (held-out evaluations go to the objective itself and are not charged)."""

    def __init__(self, objective: Objective) -> None:
        self.objective = objective
        self.count = 0

    def evaluate(self, pop: Any, split: str = "train") -> Evaluation:
        """The wrapped objective's `Objective.evaluate`; the rows of ``pop`` are counted on ``"train"``."""
        ev = self.objective.evaluate(pop, split)
        if split == "train":
            self.count += int(np.atleast_2d(np.asarray(pop)).shape[0])
        return ev

    def __getattr__(self, name: str) -> Any:
        return getattr(self.objective, name)


def build_study_objective(cfg: StudyConfig) -> Objective:
    """The study's `Objective`: each map's (train and held-out split disjoint, checked), joined over the maps.

    Raises:
      ValueError: a map whose train and held-out splits share seeds or a (start, goal) row.
    """
    from jaxplan.experiments import load_map_spec, spec_scenarios

    t0 = cfg.tunes[0]
    if t0.kind == "nav":
        # One navigation objective over every map: its `evaluate` runs the maps one compiled call each (a join of
        # per-map objectives would evaluate the first map's episodes only); it checks rows and seeds disjoint.
        t = dataclasses.replace(t0, maps=tuple(m for one in cfg.tunes for m in one.maps),
                                test_count=cfg.held_out_count if cfg.held_out_count is not None else t0.test_count)
        return dataclasses.replace(build_objective(t), name=cfg.name, _compiled={})
    objs = []
    for t in cfg.tunes:
        if cfg.held_out_count is not None:
            t = dataclasses.replace(t, test_count=cfg.held_out_count)
        grid, s0, g0, _ = load_map_spec(t.map)
        starts, goals, optimal, _ = spec_scenarios(t.map, grid, s0, g0)
        train, test = split_scenarios(t, grid, starts, goals, optimal)
        check_disjoint(train, test, t.map.name)
        if cfg.gap == "own":
            space = {k: (list(v) if isinstance(v, list) else tuple(v)) for k, v in t.space.items()}
            o = aco_own_objective(grid, train, test, t.planner, space, dict(t.weights), dict(t.overrides),
                                  name=f"{cfg.name}:{t.map.name}")
        else:
            o = dataclasses.replace(build_objective(t), name=f"{cfg.name}:{t.map.name}")
        objs.append(o)
    return concat_objectives(objs, name=cfg.name)
