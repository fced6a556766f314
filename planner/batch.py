"""plan_batch: plan many (start, goal) pairs on one cost, in this process or as tasks on a dask cluster."""

from __future__ import annotations

import copy
import dataclasses
import math
import time
from typing import Any

from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.dask_client import Compute, client_worker_count, run_tasks
from terrawatt_base.errors import InvalidParameterError

from .batch_pairs import BatchPairs
from .batch_result import BatchResult, BatchRow
from .cache import CACHE_SIZE, ResultCache
from .cost_spec import CostSpec
from .edge_cost import EnergyCost
from .planning import RouteSearch
from .warmup import warm_up_kernels

__all__ = ["plan_batch", "plan_batch_on_map", "plan_pair", "shippable_cost"]


def plan_pair(
    cost: EnergyCost,
    name: str,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    search: RouteSearch,
) -> BatchRow:
    """Plan one pair with its comparison (:meth:`RouteSearch.plan` with ``compare=True``) as a :class:`BatchRow`.

    The task of :func:`plan_batch` (module-level, so dask workers import it by reference).
    Errors propagate: the caller turns them into an ``"error"`` row.
    """
    route = search.plan(cost, start_xy_m, goal_xy_m, compare=True)
    found = route.found
    nan = math.nan
    return BatchRow(
        name=name, start_x_m=float(start_xy_m[0]), start_y_m=float(start_xy_m[1]),
        goal_x_m=float(goal_xy_m[0]), goal_y_m=float(goal_xy_m[1]), status=route.status,
        energy_j=route.energy_j if found else nan, energy_wh=route.energy_wh if found else nan,
        length_m=route.length_m if found else nan, duration_s=route.duration_s if found else nan,
        shortest_energy_j=route.shortest_energy_j, energy_saved_pct=route.energy_saved_pct,
        planning_time_s=route.planning_time_s,
    )


def _error_row(name: str, start_xy_m: Any, goal_xy_m: Any, exc: BaseException) -> BatchRow:
    return BatchRow(name=name, start_x_m=float(start_xy_m[0]), start_y_m=float(start_xy_m[1]),
                    goal_x_m=float(goal_xy_m[0]), goal_y_m=float(goal_xy_m[1]), status="error",
                    error=f"{type(exc).__name__}: {exc}")


def _plan_pair_task(cost: EnergyCost, name: str, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float],
                    search: RouteSearch) -> BatchRow:
    """:func:`plan_pair`, a pair whose planning raises (a blocked start, ...) returned as an ``"error"`` row.

    Returning the row rather than raising keeps the other pairs going and a dask worker from
    logging the expected failure with a traceback.
    """
    try:
        return plan_pair(cost, name, start_xy_m, goal_xy_m, search)
    except Exception as exc:  # noqa: BLE001 - a pair that raises is reported in its row, the others go on
        return _error_row(name, start_xy_m, goal_xy_m, exc)


def shippable_cost(cost: EnergyCost) -> EnergyCost:
    """A shallow copy of ``cost`` without its caches (lattice graphs, results): what goes to the workers.

    Each worker builds the lattice graph once, on its first task, and keeps it on its copy.
    """
    shipped = copy.copy(cost)
    shipped.lattices = {}
    shipped.results = ResultCache(CACHE_SIZE)
    return shipped


def plan_batch(
    cost: EnergyCost,
    pairs: Any,
    *,
    search: RouteSearch | None = None,
    compute: Compute | None = None,
) -> BatchResult:
    """Plan many (start, goal) pairs on one cost: here, on a local dask cluster, or on a given client.

    Every pair is planned by :func:`planner.plan_route` with ``compare=True`` (its saving against the
    shortest route). On dask, each pair is one task; the cost (map and tables, without its
    caches) is sent to every worker once (:func:`~terrawatt_base.dask_client.run_tasks`), never
    with a task, and each worker builds the lattice graph once. A pair whose planning raises
    (e.g. a start on an obstacle) becomes a row of status ``"error"`` with the exception's
    text; the other pairs are planned as usual. Rows come back in the order of the pairs,
    whichever task finishes first, so a batch gives the same rows in process and on any
    number of workers (the lattice planner is deterministic; OMPL planners need ``seed``
    and ``max_cost_evaluations`` with ``time_limit_s=None`` in the search for that).

    Parameters
    ----------
    cost : EnergyCost
        Edge costs of the map (the map is ``cost.terrain``).
    pairs : BatchPairs or array-like
        :class:`BatchPairs` (e.g. :func:`read_pairs_csv`, :meth:`BatchPairs.all_pairs`,
        ``BatchPairs.from_array(array, names)`` to name them), an ``(N, 4)`` array
        ``[start_x_m, start_y_m, goal_x_m, goal_y_m]`` or ``(N, 2, 2)`` (named ``"0"``, ``"1"``, ...).
    search : RouteSearch, optional
        The planner, its budget, seed and tuning (:class:`planner.planning.RouteSearch`);
        default ``RouteSearch("lattice")``: exact, deterministic and fast (the lattice planner
        ignores the budget; the seed seeds the refinement).
    compute : Compute, optional
        Where the pairs are planned and whether a bar shows over them
        (:class:`terrawatt_base.dask_client.Compute`; default: here, one after another, no bar).

    Returns
    -------
    BatchResult

    Raises
    ------
    InvalidParameterError
        Not an EnergyCost; pairs of a bad shape, NaN coordinates, bad names; not a
        ``RouteSearch`` or a ``Compute``; an unreachable scheduler (after a timeout).
    OptionalDependencyError
        A cluster is asked for but dask.distributed is not installed.

    Examples
    --------
    >>> from terrain import flat_map
    >>> cost = CostSpec().build(flat_map((20, 20), 1.0))
    >>> res = plan_batch(cost, [[2.0, 2.0, 15.0, 12.0], [15.0, 12.0, 2.0, 2.0]])
    >>> [r.status for r in res.rows], round(res.rows[0].length_m, 2)
    (['exact', 'exact'], 16.4)
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    batch = BatchPairs.from_array(pairs)
    search = RouteSearch("lattice") if search is None else check_instance("search", search, RouteSearch)
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    tasks = [(_plan_pair_task, (batch.names[i], tuple(batch.starts_xy_m[i].tolist()),
                                tuple(batch.goals_xy_m[i].tolist()), search)) for i in range(len(batch))]
    with compute.session() as (client, where):
        t0 = time.perf_counter()
        # the workers get the cost without its caches, once; here the caller's cost keeps what it learns
        shared = (cost if client is None else shippable_cost(cost),)
        rows = list(run_tasks(tasks, client=client, shared=shared, progress=compute.progress, description="routes",
                              on_error=lambda i, exc: _error_row(batch.names[i], batch.starts_xy_m[i],
                                                                 batch.goals_xy_m[i], exc)))
        n_used = client_worker_count(client)
        elapsed = time.perf_counter() - t0
    return BatchResult(tuple(rows), search.planner, where, n_used, elapsed, terrain=cost.terrain)


def plan_batch_on_map(
    terrain: TerrainMap,
    pairs: BatchPairs | Any,
    *,
    search: RouteSearch | None = None,
    pricing: CostSpec | None = None,
    compute: Compute | None = None,
    map_label: str = "map",
) -> BatchResult:
    """Price ``terrain`` (:meth:`planner.cost_spec.CostSpec.build`) and plan every pair on it (:func:`planner.plan_batch`).

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    pairs : BatchPairs or array-like
        As :func:`planner.plan_batch`.
    search, compute
        As :func:`planner.plan_batch`.
    pricing : CostSpec, optional
        How the edges are priced (:class:`planner.cost_spec.CostSpec`, default ``CostSpec()``; its
        ``risk`` is not used: every pair at the mean).
    map_label : str
        How the map is named.

    Returns
    -------
    BatchResult
        With ``map_label`` and the map.

    Raises
    ------
    TerrawattError
        As :meth:`planner.cost_spec.CostSpec.build` and :func:`planner.plan_batch`.

    Examples
    --------
    >>> from terrain import flat_map
    >>> report = plan_batch_on_map(flat_map((20, 20), 1.0), [[2.0, 2.0, 15.0, 12.0]])
    >>> report.all_found, report.header()
    (True, 'map: map  20 x 20 cells of 1 m; 1 pairs; planner lattice')
    """
    pricing = CostSpec.given(pricing)
    cost = pricing.build(terrain)
    warm_up_kernels()
    result = plan_batch(cost, pairs, search=search, compute=compute)
    return dataclasses.replace(result, map_label=map_label)
