"""Many pairs planned on one map priced from names, reported: the printed table, batch.csv and batch.json (BatchReport)."""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from terrain import TerrainMap
from terrawatt_base.checks import check_instance

from .batch import plan_batch
from .batch_pairs import BatchPairs
from .batch_result import BatchResult
from .cost_spec import CostSpec
from .warmup import warm_up_kernels

__all__ = ["BatchReport", "plan_batch_on_map"]


@dataclass(frozen=True)
class BatchReport:
    """A :class:`BatchResult` with the map it was planned on, ready to print and write.

    Made by :func:`plan_batch_on_map`. :meth:`summary` is the text ``terrawatt batch`` prints,
    :meth:`write` writes batch.csv and batch.json.

    Attributes
    ----------
    result : BatchResult
        One row per pair.
    map_label : str
        How the map is named.
    planner : str
        The planner of every pair.
    terrain : TerrainMap
        The map.
    """

    result: BatchResult
    map_label: str
    planner: str
    terrain: TerrainMap = field(default=None, repr=False, compare=False)  # type: ignore[assignment]

    @property
    def all_found(self) -> bool:
        """Whether every pair has a route."""
        return self.result.n_found == len(self.result)

    def header(self) -> str:
        """``map: LABEL  R x C cells of S m; N pairs; planner NAME``: the first line of the summary."""
        t = self.terrain
        return (f"map: {self.map_label}  {t.shape[0]} x {t.shape[1]} cells of {t.cell_size_m:g} m; "
                f"{len(self.result)} pairs; planner {self.planner}")

    def summary(self) -> str:
        """What ``terrawatt batch`` prints: the map, the table of the pairs (:meth:`BatchResult.table`), the totals."""
        return "\n".join([self.header(), self.result.table(), "", self.result.summary()])

    def write(self, out_dir: str | os.PathLike[str]) -> list[Path]:
        """Write batch.csv and batch.json into ``out_dir`` (created); return them."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        return [self.result.to_csv(out / "batch.csv"), self.result.write_json(out / "batch.json")]


def plan_batch_on_map(
    terrain: TerrainMap,
    pairs: BatchPairs | Any,
    *,
    planner: str = "lattice",
    pricing: CostSpec | None = None,
    time_limit_s: float | None = 1.0,
    max_cost_evaluations: int | None = None,
    seed: int | None = 0,
    client: Any = None,
    where: str | None = None,
    progress: bool = True,
    map_label: str = "map",
) -> BatchReport:
    """Price ``terrain`` (:meth:`planner.cost_spec.CostSpec.build`) and plan every pair on it (:func:`planner.plan_batch`).

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    pairs : BatchPairs or array-like
        As :func:`planner.plan_batch`.
    planner, time_limit_s, max_cost_evaluations, seed, client, progress
        As :func:`planner.plan_batch`; ``where`` says how the result names ``client``'s cluster.
    pricing : CostSpec, optional
        How the edges are priced (:class:`planner.cost_spec.CostSpec`, default ``CostSpec()``; its
        ``risk`` is not used: every pair at the mean).
    map_label : str
        How the map is named.

    Returns
    -------
    BatchReport

    Raises
    ------
    TerrawattError
        As :meth:`planner.cost_spec.CostSpec.build` and :func:`planner.plan_batch`.

    Examples
    --------
    >>> from terrain import flat_map
    >>> report = plan_batch_on_map(flat_map((20, 20), 1.0), [[2.0, 2.0, 15.0, 12.0]], progress=False)
    >>> report.all_found, report.header()
    (True, 'map: map  20 x 20 cells of 1 m; 1 pairs; planner lattice')
    """
    pricing = CostSpec() if pricing is None else check_instance("pricing", pricing, CostSpec)
    cost = pricing.build(terrain)
    warm_up_kernels()
    result = plan_batch(cost, pairs, planner=planner, seed=seed, client=client, time_limit_s=time_limit_s,
                        max_cost_evaluations=max_cost_evaluations, progress=progress)
    if client is not None and where is not None:  # where it ran, as the caller names it
        result = dataclasses.replace(result, where=where)
    return BatchReport(result=result, map_label=map_label, planner=planner, terrain=terrain)
