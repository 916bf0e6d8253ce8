"""The five papers jaxplan implements, named by first author and year.

Code, configs, generators and figure folders refer to a paper by its ``key`` (``cui2025``);
a reproduction config is ``configs/<key>_<table>.toml``. Full citations and what each paper
contributes: ``docs/papers.md``. This module is pure data and imports nothing from jaxplan.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["Paper", "PAPERS", "paper"]


class Paper(NamedTuple):
    """One paper.

    Attributes:
      key: first author's surname and year, lower case (``cui2025``).
      authors: the author list as printed.
      year: publication year.
      title: the title.
      venue: journal (volume, article) as far as our copy states it.
      doi: DOI without the resolver prefix, or ``""`` where our copy prints none.
      adds: what jaxplan takes from it, in one line.
      planners: the registered planners and pipelines it contributes.
    """

    key: str
    authors: str
    year: int
    title: str
    venue: str
    doi: str
    adds: str
    planners: tuple[str, ...]

    @property
    def short(self) -> str:
        """``Cui & Liu (2025)``: the first author, "& second" for two authors, "et al." for more."""
        names = [a.strip().split()[-1] for a in self.authors.replace(" and ", ", ").split(",") if a.strip()]
        who = names[0] if len(names) == 1 else f"{names[0]} & {names[1]}" if len(names) == 2 else f"{names[0]} et al."
        return f"{who} ({self.year})"


PAPERS: dict[str, Paper] = {p.key: p for p in (
    Paper("cui2025", "Ruiling Cui, Hongli Liu", 2025,
          "A Two-Level Path Planning Approach Combining Improved ACO and DWA for Mobile Robots in Warehousing "
          "Environments", "journal not named in our copy (received 1 August 2025)", "",
          "elite multi-objective ACO (IACO) and a fuzzy-evaluated DWA as one two-level system, with its ablations",
          ("iaco", "iaco_dwa", "aco_dwa")),
    Paper("li2026", "Jianjun Li, Ji Xiang", 2026,
          "Dynamic Route Planning for Warehouse Robots Combining A-Star and Dynamic Window Approach",
          "Journal of Engineering, Project, and Production Management", "10.32738/JEPPM-2025-213",
          "A* with key-node guidance, multi-region biased RRT* sampling, the improved sparrow search (ISSA) "
          "for tuning, multi-robot runs among moving obstacles",
          ("astar_kng", "mrbs_rrt", "astar_kng_dwa", "mrbs_rrt_dwa")),
    Paper("chu2024", "Liyang Chu, Haifeng Guo, Qingshi Meng", 2024,
          "Intelligent Logistics Vehicle Path Planning Using Fused Optimization Ant Colony Algorithm With Grid",
          "International Journal of Information Technologies and Systems Approach (IJITSA)", "10.4018/IJITSA.342613",
          "terrain-aware 'Opt Ant': height grids, 16-direction moves, right-turn rules, dead-end alerts, "
          "Bezier corners",
          ("opt_ant", "opt_ant_dwa")),
    Paper("chen2023", "Yun Chen, Jinfeng Wu, Chaoshuai He, Si Zhang", 2023,
          "Intelligent Warehouse Robot Path Planning Based on Improved Ant Colony Algorithm",
          "IEEE Access (our copy prints no volume or date)", "",
          "risk-aware ACO on Poisson 'unknown factor' maps, obstacle-aware initial pheromone, arc fillets",
          ("risk_aco",)),
    Paper("yu2020", "Junqi Yu, Ruolin Li, Zengxi Feng, Anjun Zhao, Zirui Yu, Ziyan Ye, Junfeng Wang", 2020,
          "A Novel Parallel Ant Colony Optimization Algorithm for Warehouse Path Planning",
          "Journal of Control Science and Engineering, vol. 2020, article 5287189", "10.1155/2020/5287189",
          "parallel ranking ACO (P-RACO) with sub-colonies on a ring, a TSP mode, line-of-sight smoothing",
          ("praco",)),
)}


def paper(key: str) -> Paper:
    """The paper named ``key``.

    Raises:
      ValueError: no such paper (the message lists the keys).
    """
    try:
        return PAPERS[key]
    except KeyError:
        raise ValueError(f"unknown paper {key!r}; known: {', '.join(PAPERS)}") from None
