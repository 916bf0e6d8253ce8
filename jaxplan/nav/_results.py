"""What two-level navigation returns: `Episode` (one robot's episode) and `EpisodeBatch` (a batched call's
episodes, ``[E scenarios, R seeds, N robots]``), numpy arrays on the host."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import numpy as np

from jaxplan.nav._moving import MovingObstacles, trajectories

__all__ = ["Episode", "EpisodeBatch"]


class Episode(NamedTuple):
    """One robot's navigation episode (numpy; docs/guide/navigation.md).

    Attributes:
      trajectory: ``f32[T + 1, 3]`` poses (x, y, theta) in m, rad, from the start; ``T``
        control steps were taken.
      controls: ``f32[T, 2]`` (v, omega) applied at each step (chu2024's velocity traces).
      times: ``f32[T + 1]`` seconds of the trajectory samples.
      success: goal reached within tolerance, without collision, within the time limit.
      reason: ``"goal"``, ``"collision"``, ``"time limit"`` or why it was not run (infeasible).
      collisions: contacts with the map, moving discs or other robots: ``active_contacts +
        passive_contacts`` (active: begun while the robot moved faster than 0.05 m/s; passive: at rest).
      time_s: simulated time until the robot stopped (s).
      metrics: the episode metrics (docs/guide/smoothing-and-metrics.md) (see `EpisodeBatch.METRICS`).
      plan: global path ``f64[L, 2]`` in cell coordinates (empty if the planner failed).
      waypoints: ``f32[K, 2]`` the waypoints tracked at first (m); ``final_waypoints`` after re-plans.
      obstacles: the `MovingObstacles` of the episode; ``obstacle_positions f32[T + 1, M, 2]``.
    """

    trajectory: np.ndarray
    controls: np.ndarray
    times: np.ndarray
    success: bool
    reason: str
    collisions: int
    time_s: float
    metrics: dict
    plan: np.ndarray
    waypoints: np.ndarray
    final_waypoints: np.ndarray
    obstacles: MovingObstacles
    obstacle_positions: np.ndarray
    active_contacts: int = 0
    passive_contacts: int = 0

    def to_dict(self) -> dict:
        """Every field as built-in Python (`jaxplan.core.export.plain`): trajectory ``[[x, y, theta], ...]``, the
        obstacles' routes as a dict of lists, metrics as numbers."""
        from jaxplan.core.export import plain

        return plain(self._asdict())

    def to_dataframe(self, what: str = "summary") -> Any:
        """A `pandas.DataFrame` (pandas: ``pip install 'jaxplan[export]'``).

        Args:
          what: ``"summary"`` one row (success, reason, collisions, time_s and the metrics);
            ``"trajectory"`` one row per pose (``step``, ``t`` s, ``x``, ``y`` m, ``theta`` rad, and the control
            ``v``, ``omega`` applied from it, NaN at the last pose).
        """
        from jaxplan.core.export import check_what, frame

        check_what(what, ("summary", "trajectory"), "Episode")
        if what == "trajectory":
            tr, u = np.asarray(self.trajectory), np.asarray(self.controls)
            T = len(tr)
            v, w = np.full(T, np.nan), np.full(T, np.nan)
            v[: len(u)], w[: len(u)] = u[:, 0], u[:, 1]
            return frame({"step": np.arange(T), "t": np.asarray(self.times), "x": tr[:, 0], "y": tr[:, 1],
                          "theta": tr[:, 2], "v": v, "omega": w})
        row = {"success": bool(self.success), "reason": self.reason, "collisions": int(self.collisions),
               "active_contacts": int(self.active_contacts), "passive_contacts": int(self.passive_contacts),
               "time_s": float(self.time_s)}
        row.update({k: v for k, v in self.metrics.items() if k not in row})
        return frame({k: [v] for k, v in row.items()})


class EpisodeBatch(NamedTuple):
    """Episodes of a batched call, leading axes ``[E scenarios, R seeds, N robots]`` (numpy).

    Attributes:
      states: ``f32[E, R, N, S + 1, 5]``; ``steps [E, R, N]`` valid control steps each.
      controls: ``f32[E, R, N, S, 2]``; ``recovery bool[E, R, N, S]``.
      reason: ``object[E, R, N]`` strings; ``feasible bool[E, R, N]`` (infeasible episodes
        were not run); ``success``, ``collisions`` (= ``active_contacts + passive_contacts``: contacts begun
        while the robot moved faster than 0.05 m/s, or at rest), ``pair_collisions [E, R, N, N]``,
        ``time_s`` (simulated), ``rmse``, ``max_curvature``, ``energy``, ``path_length``
        (executed, m), ``recoveries``, ``replans``: ``[E, R, N]``.
      plans: ``f64[E, R, N, P, 2]`` global paths in cell coordinates (grid paths, or a sampling
        planner's any-angle polyline), −1 padded, with ``n_plan``.
      waypoints: ``f32[E, R, N, K, 2]`` (m) with ``n_waypoints``; ``final_waypoints`` /
        ``n_final_waypoints`` after re-plans.
      obstacles: `MovingObstacles` with leaves ``[E, R, M, …]``.
      obstacle_positions: ``f32[E, R, S + 1, M, 2]`` where the obstacles were after each step when some walkers
        see (simulated, not on their routes), or None (positions follow from the routes).
      give_ways: ``i32[E, R, N]`` times each robot gave way (`jaxplan.NavConfig.give_way`; zero when off).
      plan_time_s: global planning wall time per episode (s, compilation excluded).
      step_time_s: wall time per control step of one robot (s): the episode call's time
        over the robot-steps it ran (compilation excluded).
      run_time_s, compile_s: the episode call's wall time and its compile time.
      period: control period (s); pipeline: the pipeline's name; resolution: m per cell.
    """

    states: np.ndarray
    steps: np.ndarray
    controls: np.ndarray
    recovery: np.ndarray
    reason: np.ndarray
    feasible: np.ndarray
    success: np.ndarray
    collisions: np.ndarray
    active_contacts: np.ndarray
    passive_contacts: np.ndarray
    pair_collisions: np.ndarray
    time_s: np.ndarray
    rmse: np.ndarray
    max_curvature: np.ndarray
    energy: np.ndarray
    path_length: np.ndarray
    recoveries: np.ndarray
    replans: np.ndarray
    plans: np.ndarray
    n_plan: np.ndarray
    waypoints: np.ndarray
    n_waypoints: np.ndarray
    final_waypoints: np.ndarray
    n_final_waypoints: np.ndarray
    obstacles: MovingObstacles
    plan_time_s: float
    step_time_s: float
    run_time_s: float
    compile_s: float
    period: float
    pipeline: str
    resolution: float
    obstacle_positions: np.ndarray | None = None
    give_ways: np.ndarray | None = None

    # Not annotated: typing.NamedTuple makes every annotated name a field (a ClassVar too, at run time).
    METRICS = ("success", "collisions", "active_contacts", "passive_contacts", "time_s", "rmse", "max_curvature",
               "energy", "path_length", "recoveries", "replans")

    def episode(self, e: int = 0, r: int = 0, i: int = 0) -> Episode:
        """Scenario ``e``, seed ``r``, robot ``i`` as an `Episode`."""
        T = int(self.steps[e, r, i])
        st = self.states[e, r, i, : T + 1]
        times = np.arange(T + 1, dtype=np.float32) * self.period
        obs = jax.tree_util.tree_map(lambda x: np.asarray(x[e, r]), self.obstacles)
        # Over the batch's full step range, so every episode of a batch shares one compiled shape.
        every = np.arange(self.states.shape[3], dtype=np.float32) * self.period
        if self.obstacle_positions is not None:
            opos = np.asarray(self.obstacle_positions[e, r, : T + 1])
        elif obs.radii.shape[-1]:
            opos = np.asarray(trajectories(obs, every))[: T + 1]
        else:
            opos = np.zeros((T + 1, 0, 2), np.float32)
        m = {k: getattr(self, k)[e, r, i].item() for k in self.METRICS}
        m["plan_time_s"], m["step_time_s"] = self.plan_time_s, self.step_time_s
        return Episode(
            trajectory=st[:, :3], controls=self.controls[e, r, i, :T], times=times,
            success=bool(self.success[e, r, i]), reason=str(self.reason[e, r, i]),
            collisions=int(self.collisions[e, r, i]), time_s=float(self.time_s[e, r, i]), metrics=m,
            plan=self.plans[e, r, i, : self.n_plan[e, r, i]],
            waypoints=self.waypoints[e, r, i, : self.n_waypoints[e, r, i]],
            final_waypoints=self.final_waypoints[e, r, i, : self.n_final_waypoints[e, r, i]],
            obstacles=obs, obstacle_positions=opos, active_contacts=int(self.active_contacts[e, r, i]),
            passive_contacts=int(self.passive_contacts[e, r, i]),
        )

    def to_dict(self) -> dict:
        """Every field as built-in Python (`jaxplan.core.export.plain`): arrays as nested lists ``[E][R][N]…``
        (states and plans padded as stored: use ``steps`` and ``n_plan``)."""
        from jaxplan.core.export import plain

        return plain(self._asdict())

    def to_dataframe(self, what: str = "summary") -> Any:
        """A long-form `pandas.DataFrame` (pandas: ``pip install 'jaxplan[export]'``); ``scenario``, ``seed`` and
        ``robot`` index the call's axes.

        Args:
          what: ``"summary"`` one row per episode (feasible, reason and every metric of ``METRICS``);
            ``"trajectory"`` one row per valid state (``step``, ``t`` s, ``x``, ``y`` m, ``theta`` rad, ``v`` m/s,
            ``omega`` rad/s).
        """
        from jaxplan.core.export import check_what, frame

        check_what(what, ("summary", "trajectory"), "EpisodeBatch")
        E, R, N = self.success.shape
        if what == "summary":
            e, r, i = (a.ravel() for a in np.meshgrid(np.arange(E), np.arange(R), np.arange(N), indexing="ij"))
            cols = {"pipeline": np.full(E * R * N, self.pipeline, object), "scenario": e, "seed": r, "robot": i,
                    "feasible": self.feasible.ravel(), "reason": self.reason.ravel()}
            cols.update({k: getattr(self, k).ravel() for k in self.METRICS})
            return frame(cols)
        keep = np.arange(self.states.shape[3])[None, None, None, :] <= self.steps[..., None]  # [E, R, N, S + 1]
        e, r, i, k = np.nonzero(keep)
        st = self.states[e, r, i, k]
        return frame({"scenario": e, "seed": r, "robot": i, "step": k, "t": k * self.period, "x": st[:, 0],
                      "y": st[:, 1], "theta": st[:, 2], "v": st[:, 3], "omega": st[:, 4]})

    def summary(self, where: np.ndarray | None = None) -> dict[str, tuple[float, float]]:
        """Mean and sd over seeds of each metric's per-seed mean over the feasible episodes (and ``where``).

        Success is a rate in [0, 1]; every other metric is averaged over the episodes it
        applies to (time over successful ones, the rest over all run ones).
        """
        mask = self.feasible if where is None else self.feasible & where
        out = {"episodes": (float(mask.sum()), 0.0), "infeasible": (float((~self.feasible).sum()), 0.0)}
        for k in self.METRICS:
            v = getattr(self, k).astype(float)
            m = mask & self.success if k == "time_s" else mask
            # Episodes that did not run (the global planner failed) have no executed metrics.
            per_seed = [np.nanmean(v[:, r][m[:, r]]) if np.isfinite(v[:, r][m[:, r]]).any() else np.nan
                        for r in range(v.shape[1])]
            per_seed = np.asarray(per_seed)
            ok = np.isfinite(per_seed)
            out[k] = (float(np.mean(per_seed[ok])) if ok.any() else math.nan,
                      float(np.std(per_seed[ok])) if ok.any() else math.nan)
        return out
