"""Tuning studies: every method against every other at an equal, counted budget, judged on held-out scenarios.

One module per job:

* `config`: the study config (``[study]`` on a tuning config; `StudyFile` is its schema), read and validated
  in full, with its quick overlay;
* `objective`: the study's objective over its maps and the wrapper that counts the training budget;
* `run`: the runs (one method × one tuner seed each, committed to the study's run folder; `study_task`: one
  run as a Ray task), workers and sessions;
* `judge`: the statistics over tuner seeds and the verdict against the defaults;
* `page`: the convergence figure and the results page;
* `confirm`: the confirmation experiment (defaults vs tuned on fresh scenarios and seeds) and its page.

Example::

    from jaxplan.tune import run_study
    folder = run_study("configs/study_iaco.toml", out="runs", quick=True)
"""

from jaxplan.tune.study.config import (
    GAPS,
    StudyConfig,
    StudyFile,
    StudyQuickTable,
    StudyTable,
    apply_study_quick,
    load_study_config,
    parse_study_config,
    quick_study_config,
)
from jaxplan.tune.study.confirm import confirm_config, own_gap_table, run_confirmation
from jaxplan.tune.study.judge import VERDICTS, interval_stats
from jaxplan.tune.study.objective import CountedObjective, build_study_objective
from jaxplan.tune.study.run import HELDOUT_FILE, STUDY_LAYOUT, run_study, study_fingerprint, study_run, study_task

__all__ = ["GAPS", "StudyConfig", "StudyFile", "StudyQuickTable", "StudyTable", "apply_study_quick",
           "load_study_config", "parse_study_config", "quick_study_config", "confirm_config", "own_gap_table",
           "run_confirmation", "VERDICTS", "interval_stats", "CountedObjective", "build_study_objective",
           "HELDOUT_FILE", "STUDY_LAYOUT", "run_study", "study_fingerprint", "study_run", "study_task"]
