"""The config schema: declared once (jaxplan.experiments.schema), its generated reference and JSON Schemas, and
the deprecated generator names."""

import dataclasses
import json
import tomllib
import warnings
from pathlib import Path

import pytest

from jaxplan import config_reference
from jaxplan.experiments import schema
from jaxplan.experiments.config import (
    FIGURE_KINDS,
    ExperimentFile,
    MapSpec,
    ObstacleSpec,
    QuickSpec,
    ScenarioSpec,
    StatsSpec,
    parse_config,
)
from jaxplan.experiments.schema import Reader, setting, settings
from jaxplan.tune import StudyFile, TuneFile

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted((ROOT / "configs").glob("*.toml"))


def _sections(root):
    """Every section class under ``root``."""
    out, todo = [], [root]
    while todo:
        cls = todo.pop()
        if cls not in out:
            out.append(cls)
            todo += [s.section for s in settings(cls) if s.section is not None]
    return out


# ---------------------------------------------------------------------------------------------
# Generated files


def test_committed_reference_and_json_schemas_are_the_generated_ones():
    stale = config_reference.write(ROOT, check=True)
    assert not stale, f"stale: {stale}; run `python -m jaxplan.config_reference` and commit the result"


def test_check_mode_names_a_stale_file_and_writes_nothing(tmp_path):
    assert config_reference.main(["--check", "--root", str(tmp_path)]) == 1
    assert not any(tmp_path.iterdir())
    assert config_reference.main(["--root", str(tmp_path)]) == 0
    assert config_reference.main(["--check", "--root", str(tmp_path)]) == 0
    assert (tmp_path / "docs" / "guide" / "config.md").read_text() == config_reference.reference_markdown()


@pytest.mark.parametrize("path", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_every_config_validates_against_its_json_schema(path):
    jsonschema = pytest.importorskip("jsonschema")
    name = {"tune": "tune.schema.json", "study": "study.schema.json"}.get(path.name.split("_")[0],
                                                                          "experiment.schema.json")
    s = json.loads((ROOT / "configs" / "schema" / name).read_text())
    jsonschema.Draft7Validator.check_schema(s)
    errors = [f"{'/'.join(map(str, e.absolute_path))}: {e.message}"
              for e in jsonschema.Draft7Validator(s).iter_errors(tomllib.loads(path.read_text()))]
    assert not errors, errors


def test_the_json_schema_flags_what_an_editor_should():
    jsonschema = pytest.importorskip("jsonschema")
    s = config_reference.schemas()[config_reference.EXPERIMENT_SCHEMA]
    bad = {"experiment": {"name": "a/b", "chunck": 4, "seeds": 0}, "maps": [{"generator": "warehouse"}],
           "planners": [{"kind": "plan", "name": "aco", "nav": {"max_tme": 1}}],
           "figures": [{"kind": "box", "band": "iqr"}], "metrics": ["lenght"]}
    found = {"/".join(map(str, e.absolute_path)) for e in jsonschema.Draft7Validator(s).iter_errors(bad)}
    assert {"experiment", "experiment/name", "experiment/seeds", "planners/0/nav", "figures/0",
            "metrics/0"} <= found, found


# ---------------------------------------------------------------------------------------------
# Declared once


@pytest.mark.parametrize("root", [ExperimentFile, TuneFile, StudyFile])
def test_every_key_has_a_type_and_a_one_line_doc(root):
    for cls in _sections(root):
        for s in settings(cls) + ((schema.extra_setting(cls),) if schema.extra_setting(cls) else ()):
            assert s.doc and "\n" not in s.doc, f"{cls.__name__}.{s.name}"
            assert not (s.required and s.default_text), f"{cls.__name__}.{s.name}: required, or a default?"


@pytest.mark.parametrize("cls", [ScenarioSpec, ObstacleSpec, StatsSpec, QuickSpec])
def test_resolved_dataclass_defaults_are_the_settings_defaults(cls):
    made = cls()
    for s in settings(cls):
        value = getattr(made, s.name)
        assert (dict(value) if s.type == "table" else value) == s.default, s.name


def test_figure_kinds_are_derived_from_the_figure_table():
    assert dict(FIGURE_KINDS) == {
        "convergence": {"band", "log", "scenario"}, "box": {"metric"}, "bar": {"metric"},
        "paths": {"scenario", "seed", "smoothing"}, "trajectories": {"scenario", "seed"},
        "pheromone": {"scenario", "seed", "log"}, "diversity": {"band", "log", "scenario"},
        "fan": {"scenario", "seed", "steps"}, "controls": {"scenario", "seed"}, "sweep": {"metric", "x", "xlabel"},
        "tours": {"seed"}}


# ---------------------------------------------------------------------------------------------
# The generic reader


@dataclasses.dataclass(frozen=True)
class _Disc:
    """A test section."""

    n: int = setting("int", 0, "discs", ge=0)
    speed: float = setting("float", 1.0, "m/s", gt=0, le=5)
    mode: str = setting("str", "bounce", "motion", choices=("bounce", "loop"), aliases={"bouncing": "bounce"})
    tag: str = setting("str", None, "a name", pattern=r"[a-z]+", hint="lower case")
    seeds: tuple = setting("seeds", 3, "seeds")
    extra: dict = setting("table", doc="free keys")
    colour: str = setting("str", None, "only for loops", when=("mode", ("loop",)))


def test_reader_reports_every_problem_with_its_key_path_and_a_close_match():
    r = Reader()
    got = r.section({"n": -1, "sped": 2.0, "speed": 9, "mode": "lop", "tag": "A1", "seeds": [1, 1], "extra": 3},
                    "discs[2]", _Disc)
    assert r.problems == [
        "discs[2].sped: unknown key; did you mean 'speed'?",
        "discs[2].n: must be >= 0, got -1",
        "discs[2].speed: must be <= 5, got 9.0",
        "discs[2].mode: must be one of 'bounce', 'loop', got 'lop'; did you mean 'loop'?",
        "discs[2].tag: must match [a-z]+ (lower case), got 'A1'",
        "discs[2].seeds: seeds must be distinct",
        "discs[2].extra: expected a table, got integer 3",
    ]
    assert got == {"n": 0, "speed": 1.0, "mode": "bounce", "tag": None, "seeds": (0, 1, 2), "extra": {},
                   "colour": None}


def test_reader_types_defaults_aliases_and_conditional_keys():
    r = Reader()
    assert r.section(None, "d", _Disc, defaults={"n": 7}) == {
        "n": 7, "speed": 1.0, "mode": "bounce", "tag": None, "seeds": (0, 1, 2), "extra": {}, "colour": None}
    with pytest.warns(DeprecationWarning, match="'bouncing' is deprecated; use 'bounce'"):
        assert r.section({"mode": "bouncing", "speed": 2}, "d", _Disc)["speed"] == 2.0
    assert r.section({"n": True, "speed": float("nan"), "mode": "loop", "colour": "red"}, "d", _Disc)["colour"] == "red"
    assert r.problems == ["d.n: expected an integer, got boolean True", "d.speed: must be a finite number, got nan"]
    r = Reader()
    r.section({"colour": "red"}, "d", _Disc)
    assert len(r.problems) == 1 and r.problems[0].startswith("d.colour: unknown key")  # mode is "bounce"


def test_markdown_and_json_schema_of_a_section():
    text, anchors = schema.markdown(_Disc, "Discs", level=3)
    assert "| `speed` | number | `1.0` | > 0, <= 5 | m/s |" in text
    assert "deprecated: `\"bouncing\"` (now `\"bounce\"`)" in text and "only where `mode` is `\"loop\"`" in text
    assert anchors == {_Disc: "discs"}
    js = schema.json_schema(_Disc, "discs")
    assert js["properties"]["speed"] == {"type": "number", "exclusiveMinimum": 0, "maximum": 5, "description": "m/s",
                                         "default": 1.0}
    loop = next(rule["then"] for rule in js["allOf"] if rule["if"]["properties"]["mode"] == {"const": "loop"})
    assert js["additionalProperties"] is False and loop["propertyNames"]["enum"][-1] == "colour"


# ---------------------------------------------------------------------------------------------
# Quick tables as an overlay declared in the schema


@dataclasses.dataclass(frozen=True)
class _Site:
    name: str
    count: int | None


@dataclasses.dataclass(frozen=True)
class _Run:
    label: str
    kind: str
    overrides: object = dataclasses.field(default_factory=lambda: schema.frozen({}))


@dataclasses.dataclass(frozen=True)
class _Cfg:
    seeds: tuple
    chunk: int
    sites: tuple
    runs: tuple


@schema.declaration
class _Quick:
    """A quick table using every overlay."""

    seeds: object = setting("seeds", None, "seeds", overlay="set")
    chunk: int = setting("int", None, "chunk", ge=1, overlay="set")
    count: int = setting("int", None, "at most this many", ge=1, overlay="cap sites[].count")
    overrides: object = setting("table", doc="merged into the runs that take the key", overlay="merge runs[].overrides")
    runs: tuple = setting("strings", None, "only these runs", overlay="keep runs[].label")
    note: str = setting("str", None, "not an overlay: ignored by it")


def _cfg():
    return _Cfg((0, 1, 2), 16, (_Site("a", None), _Site("b", 5), _Site("c", 1)),
                (_Run("A", "plan", schema.frozen({"x": 1})), _Run("B", "navigate"), _Run("C", "plan")))


def test_overlay_sets_caps_merges_and_keeps_as_declared():
    cfg = _cfg()
    q = Reader().section({"seeds": 2, "count": 3, "overrides": {"y": [1, 2]}, "runs": ["A", "B"], "note": "n"},
                         "quick", _Quick)
    got = schema.overlay(cfg, q, _Quick, where={"overrides": lambda run, k: run.kind == "plan"})
    assert got.seeds == (0, 1) and got.chunk == 16
    assert [s.count for s in got.sites] == [3, 3, 1]  # unset takes the cap; only larger counts are lowered
    assert [r.label for r in got.runs] == ["A", "B"]  # C filtered out after the merge
    assert dict(got.runs[0].overrides) == {"x": 1, "y": (1, 2)} and dict(got.runs[1].overrides) == {}
    assert cfg == _cfg()  # the original is not changed


def test_overlay_skips_absent_and_empty_keys_and_reads_attributes():
    cfg = _cfg()
    assert schema.overlay(cfg, {"seeds": None, "overrides": {}, "runs": []}, _Quick) == cfg

    @dataclasses.dataclass(frozen=True)
    class Values:
        chunk: int = 4
        runs: tuple = ("C",)

    got = schema.overlay(cfg, Values(), _Quick)
    assert got.chunk == 4 and [r.label for r in got.runs] == ["C"] and got.sites == cfg.sites


def test_an_overlay_must_name_a_known_operation():
    with pytest.raises(ValueError, match="overlay must start with one of set, merge, cap, keep"):
        schema.Setting("int", overlay="add count")


def test_every_quick_table_declares_an_overlay_for_each_key():
    for section in _sections(ExperimentFile):
        if section.__name__.endswith(("Quick", "QuickSpec", "QuickTable")):
            assert all(s.overlay is not None for s in settings(section)), section


# ---------------------------------------------------------------------------------------------
# Deprecated generator names (renamed after the papers' authors in this release)


_GEN = """
[experiment]
name = "dep"
seeds = 1
[[maps]]
generator = "{gen}"
{params}
scenarios = {{ source = "scene" }}
[[planners]]
kind = "plan"
name = "astar"
"""


@pytest.mark.parametrize("old, new, params", [
    ("warehouse_seed003", "warehouse_chen2023", ""),
    ("warehouse_seed004", "warehouse_yu2020", "params = { size = 35 }"),
    ("warehouse_seed003_risk", "warehouse_chen2023_risk", "params = { lam = 2.0 }"),
])
def test_old_generator_names_still_load_with_a_deprecation_warning(old, new, params, tmp_path):
    with pytest.warns(DeprecationWarning, match=rf"maps\[0\]\.generator: '{old}' is deprecated; use '{new}'"):
        got = parse_config(_GEN.format(gen=old, params=params), data_dir=tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        want = parse_config(_GEN.format(gen=new, params=params), data_dir=tmp_path)
    assert isinstance(got.maps[0], MapSpec) and got.maps[0] == want.maps[0] and got.maps[0].generator == new
