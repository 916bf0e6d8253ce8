"""The reproduction configs (configs/seed*.toml): each validates, stores the paper's numbers and documents its
deviations; `jaxplan reproduce --quick` runs them all and draws their figures (in CI: about 2 min on 2 cores; the issue's
budget for all quick runs together is 3 min)."""

from __future__ import annotations

from pathlib import Path

import pytest

from jaxplan.cli import main
from jaxplan.experiments.config import load_config
from jaxplan.experiments.reproduce import reproduction_configs

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = reproduction_configs(ROOT / "configs")
SEEDS = ("seed000", "seed001", "seed002", "seed003", "seed004")


def test_every_seed_has_a_reproduction_config():
    names = [p.name for p in CONFIGS]
    assert all(any(n.startswith(s) for n in names) for s in SEEDS), names


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.stem)
def test_reproduction_config_is_complete(path):
    cfg = load_config(path)
    assert cfg.paper and cfg.paper_source.startswith("Seed 00"), "the paper's numbers, labelled with their table"
    assert cfg.quick.seeds and cfg.figures
    assert "Deviations from the paper" in path.read_text()


def test_reproduce_quick_runs_every_config_and_draws_its_figures(tmp_path, capsys):
    rc = main(["reproduce", "--quick", "--configs", str(ROOT / "configs"), "--out", str(tmp_path / "runs"),
               "--figures", str(tmp_path / "figures"), "--no-progress", "--no-cache"])
    out = capsys.readouterr().out
    assert rc == 0, out
    index = (tmp_path / "figures" / "index.md").read_text()
    for p in CONFIGS:
        run = tmp_path / "runs" / f"{load_config(p).name}-quick"
        assert (run / "trials.csv").is_file() and (run / "report.md").is_file()
        assert f"({run.name}/index.md)" in index
        assert "paper" in (run / "summary.md").read_text()


def test_quick_keeps_only_the_named_planners_and_maps():
    from jaxplan.experiments.config import ConfigError, apply_quick, parse_config

    text = (ROOT / "configs" / "seed004_tables2_3.toml").read_text()
    q = apply_quick(parse_config(text))
    assert [m.name for m in q.maps] == ["map30"] and [p.label for p in q.planners] == ["ACO", "P-RACO"]
    bad = text.replace('maps = ["map30"]', 'maps = ["map31"]\nplanners = ["PRACO"]')
    with pytest.raises(ConfigError) as e:
        parse_config(bad)
    assert "experiment.quick.maps[0]: unknown map 'map31'" in str(e.value)
    assert "experiment.quick.planners[0]: unknown planner 'PRACO'" in str(e.value)


def test_hausdorff_to_the_exact_path_is_zero_for_astar(tmp_path):
    import numpy as np

    from jaxplan.experiments.runner import run_experiment
    from jaxplan.experiments.stats import read_trials

    cfg = tmp_path / "h.toml"
    cfg.write_text("""
metrics = ["success", "length", "hausdorff"]
[experiment]
name = "h"
seeds = 2
chunk = 2
[[maps]]
name = "wh"
generator = "warehouse"
seed = 0
params = { width = 14, height = 10, shelf_length = 4, shelf_depth = 2, aisle = 1, cross_aisle = 2 }
[scenarios]
source = "random"
count = 2
seed = 3
min_distance = 5.0
[[planners]]
label = "A*"
kind = "plan"
name = "astar"
[[planners]]
label = "AS"
kind = "plan"
name = "aco"
overrides = { ants = 6, iterations = 3, dead_end = "retreat" }
""")
    t = read_trials(run_experiment(cfg, tmp_path / "runs", progress=False) / "trials.csv")
    astar = t["planner"] == "A*"
    assert np.all(t["hausdorff"][astar] == 0.0)
    h = t["hausdorff"][~astar & (t["success"] == 1)]
    assert h.size and np.all(np.isfinite(h) & (h >= 0))
