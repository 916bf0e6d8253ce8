"""Progress of a long run on stderr: a bar over its trials with elapsed time and time left (`jaxplan.core.progress`).

``NAME  chunk k/K MAP/PLANNER  [bar]  done/total trials  elapsed  left``: the description names the chunk being
computed (the first one includes JAX's compilation, so the first estimate of time left is pessimistic; chunks
resumed from the checkpoints are shown as done but not counted in the rate). Drawn only on a terminal and without
``--no-progress`` / ``progress=False``; the run's files are the same either way.
"""

from __future__ import annotations

from jaxplan.core.progress import ProgressBar, clock, progress_wanted

__all__ = ["clock", "progress_wanted", "Progress", "ProgressBar"]


class Progress:
    """The bar of `jaxplan.experiments.run_experiment`: ``total`` trials in ``chunks`` compiled calls, ``done`` of
    them already committed (a resumed run)."""

    def __init__(self, name: str, total: int, done: int, chunks: int, enabled: bool):
        self.name, self.total, self.chunks = name, total, chunks
        self.bar = ProgressBar(f"{name}: starting", total, done=done, unit="trials", enabled=enabled)

    @property
    def enabled(self) -> bool:
        """Whether the bar is drawn."""
        return self.bar.active

    def start(self, chunk: int, what: str) -> None:
        """Chunk ``chunk`` (1-based) of ``what`` (``MAP/PLANNER``) is being computed (compiled on first use)."""
        self.bar.stage(f"{self.name}: chunk {chunk}/{self.chunks} {what}")

    def update(self, done: int, chunk: int, what: str) -> None:
        """Chunk ``chunk`` of ``what`` is committed; ``done`` trials in all."""
        self.bar.update(done, description=f"{self.name}: chunk {chunk}/{self.chunks} {what} done")

    def close(self) -> None:
        self.bar.close()
