"""Team trials (`team = { robots = N }`): N robots in one shared episode through `jaxplan.navigate_multi`, team
metrics per trial, and the robot model chosen from the config (li2026's Ackermann robot)."""

from __future__ import annotations

import csv
import io
import math
from types import SimpleNamespace

import numpy as np
import pytest

from jaxplan.experiments.config import ConfigError, parse_config
from jaxplan.experiments.execute import run_unit
from jaxplan.experiments.prepare import _planner_doc, prepare
from jaxplan.experiments.team import team_cells, team_values

TEAM = """
metrics = ["success", "arrived", "collisions", "robot_contacts", "max_curvature", "energy", "time_s"]
[experiment]
name = "team"
seeds = 2
chunk = 2
[[maps]]
name = "wh"
generator = "warehouse"
seed = 1
params = { width = 20, height = 16, shelf_length = 4, shelf_depth = 2, aisle = 2, cross_aisle = 2 }
[scenarios]
source = "random"
count = 2
seed = 0
min_distance = 8.0
[[planners]]
label = "team"
kind = "navigate"
name = "astar_kng_dwa"
nav = { max_time = 12.0, replan = false }
dwa = { n_v = 6, n_omega = 10 }
robot = %(robot)s
obstacles = { n = 2, speed = 1.0, radius = 0.3, avoid_radius = 1.0 }
team = %(team)s
"""

ACKERMANN = '{ model = "ackermann", v_max = 1.5, accel = 0.3, decel = 0.3 }'


def _config(tmp_path, robot=ACKERMANN, team="{ robots = 5 }"):
    return parse_config(TEAM % {"robot": robot, "team": team}, data_dir=tmp_path)


@pytest.fixture(scope="module")
def team_run(tmp_path_factory):
    """The first chunk of a team of five Ackermann robots, run twice from scratch."""
    tmp = tmp_path_factory.mktemp("team")
    prep = prepare(_config(tmp))
    first = run_unit(prep, prep.units[0])
    again = run_unit(prepare(_config(tmp)), prepare(_config(tmp)).units[0])
    return prep, first, again


def _rows(text: str, prep) -> list[dict]:
    from jaxplan.experiments.prepare import trial_columns

    return list(csv.DictReader(io.StringIO(text), fieldnames=trial_columns(prep.config)))


def test_a_team_trial_is_one_episode_of_five_distinct_robots(team_run):
    prep, (text, keep, _), _ = team_run
    pos = keep["team_positions"]  # [n, R, N, T, 2]
    assert pos.shape[:3] == (2, 2, 5)
    assert np.array_equal(keep["positions"], pos[:, :, 0])  # robot 0 is kept as a single robot's trajectory
    starts = keep["team_starts"]  # [n, N, 2]: robot 0 is the scenario's start
    mw = prep.maps[0]
    assert np.array_equal(starts[:, 0], mw.starts[:2]) and np.array_equal(keep["team_goals"][:, 0], mw.goals[:2])
    for e in range(2):
        assert len({tuple(c) for c in starts[e]}) == 5  # five distinct robots
        for i in range(5):
            for j in range(i + 1, 5):
                assert not np.allclose(pos[e, 0, i], pos[e, 0, j])
    rows = _rows(text, prep)
    assert len(rows) == 4  # one row per (scenario, seed): the team
    for r in rows:
        arrived, success = float(r["arrived"]), int(r["success"])
        assert 0.0 <= arrived <= 1.0 and success == int(arrived == 1.0)
        assert int(r["robot_contacts"]) >= 0 and int(r["collisions"]) >= 0


def test_same_seed_same_team_result(team_run):
    _, (text, keep, _), (text2, keep2, _) = team_run
    assert text == text2
    assert np.array_equal(keep["team_positions"], keep2["team_positions"])


def test_ackermann_from_the_config_keeps_its_turning_radius(team_run):
    from jaxplan.dwa import Ackermann
    from jaxplan.experiments.config import nav_config

    prep, (text, keep, _), _ = team_run
    robot = nav_config(prep.config.planners[0])[0].dwa.robot
    assert isinstance(robot, Ackermann) and robot.v_max == 1.5 and robot.accel == 0.3
    limit = math.tan(robot.steer_max) / robot.wheelbase  # 1/m: the minimum turning radius's inverse
    st = keep["states"]  # robot 0: [n, R, T, 5] (x, y, theta, v, omega)
    v, w = st[..., 3], st[..., 4]
    moving = np.abs(v) > 1e-3
    assert moving.any()
    assert np.all(np.abs(w[moving]) <= limit * np.abs(v[moving]) + 1e-4)  # never turns tighter (nor in place)
    assert np.all(np.abs(w[~moving]) <= 1e-4)
    kappa = [float(r["max_curvature"]) for r in _rows(text, prep)]
    assert all(k <= limit + 1e-4 for k in kappa if not math.isnan(k))


def test_unicycle_stays_the_default(tmp_path):
    from jaxplan.dwa import Unicycle
    from jaxplan.experiments.config import nav_config

    cfg = _config(tmp_path, robot="{ v_max = 1.5 }")
    assert type(nav_config(cfg.planners[0])[0].dwa.robot) is Unicycle


def test_team_values_sum_counts_and_count_each_robot_contact_once():
    pair = np.zeros((1, 1, 3, 3), np.int32)
    pair[0, 0, 0, 1] = pair[0, 0, 1, 0] = 2  # robots 0 and 1 touched twice
    eb = SimpleNamespace(
        success=np.array([[[True, False, True]]]), collisions=np.array([[[2, 3, 0]]]), pair_collisions=pair,
        active_contacts=np.array([[[1, 2, 0]]]), passive_contacts=np.array([[[1, 1, 0]]]),
        time_s=np.array([[[5.0, np.nan, 7.0]]]), rmse=np.array([[[0.1, 0.2, 0.3]]]),
        max_curvature=np.array([[[0.5, 1.2, 0.7]]]), energy=np.array([[[10.0, 20.0, 30.0]]]),
        path_length=np.array([[[1.0, 2.0, 3.0]]]), recoveries=np.array([[[0, 1, 1]]]), replans=np.array([[[1, 0, 0]]]))
    keys = ("success", "arrived", "collisions", "robot_contacts", "active_contacts", "passive_contacts", "time_s",
            "rmse", "max_curvature", "energy", "path_length", "recoveries", "replans")
    v = {k: a[0, 0] for k, a in team_values(eb, 1, keys).items()}
    assert v["success"] == 0 and v["arrived"] == pytest.approx(2 / 3)
    assert v["collisions"] == 5 and v["robot_contacts"] == 2  # robot-robot contacts: once per pair
    assert v["active_contacts"] == 3 and v["passive_contacts"] == 2 and v["recoveries"] == 2 and v["replans"] == 1
    assert v["max_curvature"] == 1.2 and v["energy"] == 60.0 and v["path_length"] == 6.0
    assert math.isnan(v["time_s"]) and v["rmse"] == pytest.approx(0.2)


def test_teams_are_the_same_for_every_planner_and_keep_their_spacing(tmp_path):
    prep = prepare(_config(tmp_path, team="{ robots = 4, spacing = 3.0, seed = 7 }"))
    mw, team = prep.maps[0], prep.config.planners[0].team
    s, g = team_cells(mw, 0, team, 1)
    s2, g2 = team_cells(mw, 0, team, 1)
    assert np.array_equal(s, s2) and np.array_equal(g, g2) and s.shape == (4, 2)
    pts = (np.concatenate([s, g]) + 0.5) * float(mw.grid.resolution)
    d = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    own = np.eye(8, dtype=bool) | np.eye(8, k=4, dtype=bool) | np.eye(8, k=-4, dtype=bool)  # a robot's own pair
    assert d[~own].min() >= 3.0
    with pytest.raises(ValueError, match="found room for only"):
        team_cells(mw, 0, team.__class__(robots=40, spacing=6.0), 0)


@pytest.mark.parametrize("robot, team, problem", [
    (ACKERMANN, "{ robots = 1 }", "planners[0].team.robots: must be >= 2, got 1"),
    (ACKERMANN, "{ spacing = 3.0 }", "planners[0].team.robots: required key is missing"),
    (ACKERMANN, "{ robots = 5, spacing = 0.4 }", "planners[0].team.spacing: 0.4 m does not keep teammates apart"),
    (ACKERMANN, "{ robots = 5, size = 3 }", "planners[0].team.size: unknown key"),
    ('{ model = "ackerman" }', "{ robots = 5 }", "planners[0].robot.model: unknown robot model 'ackerman'"),
    ('{ wheelbase = 0.4 }', "{ robots = 5 }", "planners[0].robot.wheelbase: only applies to model = 'ackermann'"),
    ('{ model = "ackermann", steer_max = 2.0 }', "{ robots = 5 }", "steer_max must be below"),
])
def test_bad_team_and_robot_values_are_clear_errors(tmp_path, robot, team, problem):
    with pytest.raises(ConfigError) as ei:
        _config(tmp_path, robot=robot, team=team)
    assert any(problem in p for p in ei.value.problems), ei.value.problems


def test_team_refuses_single_path_metrics_and_plan_planners(tmp_path):
    text = TEAM % {"robot": ACKERMANN, "team": "{ robots = 3 }"}
    with pytest.raises(ConfigError) as ei:
        parse_config(text.replace('"time_s"]', '"time_s", "hausdorff"]'), data_dir=tmp_path)
    assert any("planners[0].team: metrics 'hausdorff'" in p for p in ei.value.problems), ei.value.problems
    plan = text + '[[planners]]\nlabel = "A*"\nkind = "plan"\nname = "astar"\nteam = { robots = 3 }\n'
    with pytest.raises(ConfigError) as ei:
        parse_config(plan.replace('"time_s"]', '"time_s", "length"]'), data_dir=tmp_path)
    assert any("planners[1].team: only applies to kind = 'navigate'" in p for p in ei.value.problems)


def test_no_team_leaves_the_fingerprint_as_before(tmp_path):
    cfg = _config(tmp_path)
    solo = cfg.planners[0].__class__(**{**cfg.planners[0].__dict__, "team": None})
    assert "team" not in _planner_doc(solo) and _planner_doc(cfg.planners[0])["team"]["robots"] == 5


def test_a_team_chunk_is_budgeted_for_every_robot(tmp_path):
    from jaxplan.experiments.budget import chunk_memory

    prep = prepare(_config(tmp_path))
    solo = prepare(_config(tmp_path).replace(planners=(prep.config.planners[0].__class__(
        **{**prep.config.planners[0].__dict__, "team": None}),)))
    assert chunk_memory(prep, 0, 0).runs == 5 * chunk_memory(solo, 0, 0).runs


def test_the_trajectories_figure_of_a_team_draws_every_robot(tmp_path):
    """Robot 0 with its global path, and each teammate's executed path from its own start."""
    from jaxplan.experiments import run_experiment
    from jaxplan.experiments.figure_kinds import DRAW
    from jaxplan.experiments.plots import plt
    from jaxplan.experiments.run_data import load_run

    text = TEAM % {"robot": ACKERMANN, "team": "{ robots = 3 }"}
    text = text.replace("seeds = 2", "seeds = 1").replace("count = 2", "count = 1")
    text += '[[figures]]\nkind = "trajectories"\n'
    (tmp_path / "team.toml").write_text(text)
    run = load_run(run_experiment(tmp_path / "team.toml", tmp_path / "runs", data_dir=tmp_path, progress=False))
    spec = run.config.figures[0]
    fig, caption = DRAW["trajectories"](run, spec)
    try:
        ax = fig.axes[0]
        mates = [ln for ln in ax.get_lines() if ln.get_color() == "tab:purple" and len(ln.get_xdata()) > 1]
        a, i = run.arrays(0, 0, 0)
        assert len(mates) == 2  # robots 1 and 2
        grid = run.prep.maps[0].grid
        for j, ln in enumerate(mates, start=1):
            steps = int(a["team_steps"][i, 0, j])
            assert np.allclose(ln.get_xydata(), a["team_positions"][i, 0, j, :steps + 1], atol=1e-5)
            assert np.allclose(ln.get_xydata()[0], grid.centre(a["team_starts"][i, j]), atol=1e-4)
        assert "team of 3 robots" in caption
    finally:
        plt.close(fig)
