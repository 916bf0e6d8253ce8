"""Deprecated: li2026's Figure 7 study moved to `jaxplan.studies.benchmark_functions` (this path works for one more
release, with a `DeprecationWarning`)."""

import warnings

from jaxplan.studies.benchmark_functions import FULL, FUNCTIONS, NAME, QUICK, StudySpec, run_study, write_study

__all__ = ["FUNCTIONS", "StudySpec", "FULL", "QUICK", "run_study", "write_study", "NAME"]

warnings.warn("jaxplan.benchmark_functions moved to jaxplan.studies.benchmark_functions; the old path works for one "
              "more release", DeprecationWarning, stacklevel=2)
