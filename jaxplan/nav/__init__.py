"""Two-level navigation (docs/guide/navigation.md): global path -> waypoints -> DWA episode among moving obstacles,
multi-robot.

* `navigate` / `navigate_batch` / `navigate_multi` (`_front`): host fronts with validation,
  the planning map inflated to d_safe, global plans, waypoints, one compiled episode call,
  metrics; results as `Episode` / `EpisodeBatch` (`_results`); argument checks (`_checks`).
* `run_episodes` (`_episode`): the pure episode program (``[B episodes, N robots]``), its state and
  inputs (`_state`), the tracking rules (`_tracking`); `run_outcomes` (`_outcomes`): the same episodes
  stepped from the host for how they ended alone, finished re-planning groups dropped as they finish.
* `NavConfig` (`_config`), `Pipeline`/`pipelines` (`_pipelines`: the seeds' systems and
  cui2025's ablations), in-episode re-planning (`_replan`).
* Moving obstacles: the motion model (`_moving`: `MovingObstacles`, `moving_obstacles`, the pure
  `obstacle_state`, padding and stacking) and the scenario generators (`_traffic`: `random_obstacles`,
  `crossing_traffic`, `head_on`).
"""

from jaxplan.nav._checks import resolve_config
from jaxplan.nav._config import NavConfig
from jaxplan.nav._episode import run_episodes
from jaxplan.nav._front import (
    PreparedEpisodes,
    navigate,
    navigate_batch,
    navigate_multi,
    planning_grid,
    prepare_episodes,
)
from jaxplan.nav._moving import (
    MovingObstacles,
    concat_obstacles,
    discs_at,
    moving_obstacles,
    no_obstacles,
    obstacle_state,
    pad_obstacles,
    stack_obstacles,
    trajectories,
    with_reactive,
)
from jaxplan.nav._outcomes import EpisodeOutcomes, run_outcomes
from jaxplan.nav._pipelines import PIPELINES, Pipeline, get_pipeline, pipelines
from jaxplan.nav._results import Episode, EpisodeBatch
from jaxplan.nav._state import REASONS, EpisodeInputs, EpisodeOutput
from jaxplan.nav._traffic import crossing_traffic, head_on, random_obstacles

__all__ = [
    "NavConfig", "REASONS", "EpisodeInputs", "EpisodeOutput", "run_episodes", "run_outcomes", "EpisodeOutcomes",
    "Episode", "EpisodeBatch", "navigate",
    "navigate_batch", "navigate_multi", "planning_grid", "prepare_episodes",
    "PreparedEpisodes", "resolve_config", "MovingObstacles", "concat_obstacles",
    "crossing_traffic", "discs_at", "head_on", "moving_obstacles", "no_obstacles", "obstacle_state",
    "pad_obstacles", "random_obstacles", "stack_obstacles", "trajectories", "with_reactive", "PIPELINES", "Pipeline",
    "get_pipeline",
    "pipelines",
]
