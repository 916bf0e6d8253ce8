"""Two-level navigation (DESIGN §5): global path -> waypoints -> DWA episode among moving obstacles, multi-robot.

* `navigate` / `navigate_batch` / `navigate_multi` (`_front`): host fronts with validation,
  the planning map inflated to d_safe, global plans, waypoints, one compiled episode call,
  metrics; results as `Episode` / `EpisodeBatch`.
* `run_episodes` (`_episode`): the pure episode program (``[B episodes, N robots]``).
* `NavConfig` (`_config`), `Pipeline`/`pipelines` (`_pipelines`: the seeds' systems and
  cui2025's ablations), in-episode re-planning (`_replan`).
* Moving obstacles (`_obstacles`): `MovingObstacles`, `moving_obstacles`, the generators
  `random_obstacles`, `crossing_traffic`, `head_on`, and the pure `obstacle_state`.
"""

from jaxplan.nav._config import NavConfig
from jaxplan.nav._episode import REASONS, EpisodeInputs, EpisodeOutput, run_episodes
from jaxplan.nav._front import (
    Episode, EpisodeBatch, navigate, navigate_batch, navigate_multi, planning_grid, resolve_config,
)
from jaxplan.nav._obstacles import (
    MovingObstacles, concat_obstacles, crossing_traffic, discs_at, head_on, moving_obstacles, no_obstacles,
    obstacle_state, pad_obstacles, random_obstacles, stack_obstacles, trajectories,
)
from jaxplan.nav._pipelines import PIPELINES, Pipeline, get_pipeline, pipelines

__all__ = [
    "NavConfig", "REASONS", "EpisodeInputs", "EpisodeOutput", "run_episodes", "Episode", "EpisodeBatch", "navigate",
    "navigate_batch", "navigate_multi", "planning_grid", "resolve_config", "MovingObstacles", "concat_obstacles",
    "crossing_traffic", "discs_at", "head_on", "moving_obstacles", "no_obstacles", "obstacle_state",
    "pad_obstacles", "random_obstacles", "stack_obstacles", "trajectories", "PIPELINES", "Pipeline", "get_pipeline",
    "pipelines",
]
