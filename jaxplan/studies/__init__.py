"""Paper studies that are not experiment configs: programs of their own, run by `jaxplan reproduce`.

* `benchmark_functions`: li2026's Figure 7, the optimisers of `jaxplan.tune` (sparrow search, its improved form,
  CMA-ES) on the classic benchmark functions, with its results page and figure.

This package sits above `jaxplan.tune` (a study runs its optimisers) and `jaxplan.experiments` (it writes its page
by the results pages' conventions), and below the command line.
"""
