"""The reproduction configs (configs/seed*.toml): each validates, stores the paper's numbers and documents its
deviations; `jaxplan reproduce --quick` runs them all and draws their figures (slow: minutes on 2 cores)."""

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


@pytest.mark.slow
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
