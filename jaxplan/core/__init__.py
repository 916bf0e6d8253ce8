"""Shared helpers at the bottom of jaxplan's import graph; this package imports nothing from jaxplan.

Its modules are imported by path (``from jaxplan.core.cache import memoize``), so that importing one
helper does not pull in JAX or numba with another:

* `jaxplan.core.cache`: the one cache of the library (`functools.lru_cache` where keys hash,
  `memoize` with content keys for maps and arrays, `Built` for "seconds spent compiling now").
* `jaxplan.core.geometry`: exact point/segment-to-unit-square distances, as numpy, JAX and numba twins.
* `jaxplan.core.io`: the one atomic write (temporary file beside the target, fsync, `os.replace`), the folder
  lock of run and tuning folders, and `confined` (a name from a config stays inside its folder).
* `jaxplan.core.failure`: how the command line ends on a failure (one line, exit code 2 bad input / 1 fault /
  130 interrupted).
* `jaxplan.core.provenance`: the one provenance record (git, CPU, versions, devices) of runs and benchmarks.
* `jaxplan.core.progress`: the progress bar of long commands and batched calls (rich or a plain line, drawn only
  on a terminal).
* `jaxplan.core.export`: results as plain Python (``to_dict``) and pandas DataFrames (``to_dataframe``).
* `jaxplan.core.xla`: compiler options for small programs stepped from Python (no XLA:CPU loop split).
* `jaxplan.core.run_folder`: the one run folder of `run`, `tune` and `study` (lock, manifest of entries with
  SHA-256, atomic writes, rebuild from records, sessions; `Payload`: what a unit of work returns for the folder's
  holder to commit).
* `jaxplan.core.markdown`: the one Markdown toolkit of the page writers (numbers, mean ± sd, intervals, tables,
  links).
* `jaxplan.core.deprecation`: the previous release's positional arguments for one release (`keyword_only`),
  `warn_deprecated`.
* `jaxplan.core.toml`: the one TOML writer (tomli-w for documents, `literal` for one inline value).
* `jaxplan.core.executor`: where independent work units run — in this process, or as Ray tasks on a cluster
  (Ray imported only there).

Layers. Imports flow strictly downward through these layers: a module may import from its own
package and from any lower layer, never from a higher one, and there is no import cycle::

    cli                                   command line
    studies                               paper studies that are programs of their own (li2026 Fig. 7)
    tune                                  objectives and optimisers over scenario batches
    experiments                           configs, runner, statistics, reports, figures
    nav                                   two-level navigation (global plan -> DWA or MPPI episodes)
    planning                              the front door `plan`/`plan_batch`/`planners` over every shipped planner
    mppi                                  the MPPI local planner (on the DWA's robot models and clearance)
    aco, smoothing, dwa                   colonies (+ TSP), path post-processing, the DWA local planner
    search                                A*/Dijkstra planners, key-node A*, RRT*/MRBS-RRT*
    registry                              the planner registry (`register_planner`, `resolve`, `run_planner_batch`)
    metrics                               path, run and episode metrics (numpy host twins included)
    grid                                  maps, move graph and exact distances, fields, collision geometry,
                                          generators
    core, papers, result, scale           shared helpers, paper keys, `PlanResult`/`BatchResult`, device meshes and
                                          memory estimates (each imports nothing from the layers above;
                                          `scale` imports only `core` from jaxplan)

The top package ``jaxplan`` re-exports the public names lazily (each on first use) and sits above
everything; modules inside jaxplan never import it (``import jaxplan as jp`` is for users, tests,
scripts and benchmarks).
Across subpackages, imports go through a package's public namespace (``from jaxplan.grid import
GridMap``), never a private module or an underscore name.
"""
