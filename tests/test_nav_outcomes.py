"""`run_outcomes`: episodes run to their ends with finished re-planning groups dropped, against `run_episodes`."""

from __future__ import annotations

import functools
from pathlib import Path

import jax
import numpy as np
import pytest

import jaxplan as jp
from jaxplan.grid import load_map, load_scenarios
from jaxplan.nav import NavConfig, prepare_episodes, run_episodes, run_outcomes

DATA = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "movingai"
if not DATA.is_dir():
    DATA = Path("/work/shared/benchmarks/movingai")
MAZE = DATA / "maze-32-32-2.map"
pytestmark = pytest.mark.skipif(not MAZE.is_file(), reason=f"MovingAI maps not found in {DATA}")

# maze-32-32-2 rows of 3.4 to 38 cells: episodes that end at very different steps
ROWS = [133, 138, 143, 149, 150, 186, 270, 300, 306, 222]
FIELDS = ("steps", "reason", "collisions", "active_contacts", "replans")


def _prepared(local: str, behavior: str, group: int):
    grid = load_map(MAZE)
    scen = load_scenarios(MAZE.with_name(MAZE.stem + "-random-1.scen"), grid)
    S, G = np.asarray(scen.starts)[ROWS], np.asarray(scen.goals)[ROWS]

    def walkers(e, seed):
        avoid = (np.stack([S[e], G[e]]).astype(float) + 0.5) * grid.resolution
        return jp.random_obstacles(grid, n=5, speed=1.0, radius=0.25, seed=10_000 * seed + e, avoid=avoid,
                                   avoid_radius=3.0, behavior=behavior)

    return prepare_episodes(grid, S, G, pipeline=f"astar_kng_{local}", seeds=[0], obstacles=walkers,
                            config=NavConfig(max_time=40.0, replan_group=group), mesh=None)


def _per_episode(params, B: int):
    """Every episode its own weights (a spread around the defaults), leading axis [B]."""
    scale = np.linspace(0.6, 1.4, B).astype(np.float32)
    return jax.tree_util.tree_map(lambda a: np.asarray(a, np.float32) * scale, params)


@pytest.mark.parametrize("local, behavior, group, per_episode", [
    ("dwa", "blind", 2, False),
    ("dwa", "social", 3, True),  # 10 episodes in groups of 3: a partial last group
    pytest.param("mppi", "social", 2, True, marks=pytest.mark.slow),
])
def test_outcomes_equal_the_episodes_and_finished_groups_are_dropped(local, behavior, group, per_episode):
    p = _prepared(local, behavior, group)
    B = p.inputs.start.shape[0]
    params = _per_episode(p.params, B) if per_episode else p.params
    full = jax.jit(functools.partial(run_episodes, p.config, p.steps, per_episode=per_episode))(
        p.table, p.free, params, p.inputs)
    programs: dict = {}
    got = run_outcomes(p.config, p.steps, p.table, p.free, params, p.inputs, per_episode, programs=programs)
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(got, f), np.asarray(getattr(full, f)), err_msg=f)
    steps = np.asarray(full.steps)[:, 0]
    assert steps.min() * 2 < steps.max()  # episodes end at different times ...
    executed = int(np.asarray(full.executed)[0])
    padded = -(-B // group) * group  # a partial last group is filled with episodes that do not run
    assert got.stepped < padded * executed  # ... and finished groups were dropped along the way
    assert len(programs) >= 2 and got.compile_s > 0
    again = run_outcomes(p.config, p.steps, p.table, p.free, params, p.inputs, per_episode, programs=programs)
    assert again.compile_s == 0.0  # the programs are reused
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(again, f), getattr(got, f), err_msg=f)


def test_a_batch_of_one_group_runs_whole():
    p = _prepared("dwa", "blind", 0)  # replan_group = 0: the whole batch shares re-planning slots
    full = jax.jit(functools.partial(run_episodes, p.config, p.steps))(p.table, p.free, p.params, p.inputs)
    got = run_outcomes(p.config, p.steps, p.table, p.free, p.params, p.inputs)
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(got, f), np.asarray(getattr(full, f)), err_msg=f)
    assert got.stepped == p.inputs.start.shape[0] * int(np.asarray(full.executed)[0])
