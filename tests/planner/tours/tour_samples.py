"""Shared samples of the tour tests: a cost with a known run-level spread, a map of hills on two grounds, a snow ridge."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from planner import CostTables, EnergyCost
from planner.cost_spec import CostSpec
from planner.tours import PairPrices
from terrain import TerrainMap

__all__ = ["with_interval", "hills_map", "hills_cost", "ridge_map", "exact_optimum", "exact_fleet_optimum"]


def with_interval(cost: EnergyCost, rel_sd: float = 0.15) -> EnergyCost:
    """``cost`` with a run-level spread of ``rel_sd`` of every mean entry (one ground's spreads shared by the run)."""
    sd = np.nan_to_num(np.abs(rel_sd * cost.tables.grade_table_j_per_m), nan=0.0, posinf=0.0)
    return cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, cost.tables.turn_table_j, ground_labels=cost.tables.ground_labels, grade_sd_table_j_per_m=sd, turn_sd_table_j=np.abs(rel_sd * cost.tables.turn_table_j)))


def hills_map() -> TerrainMap:
    """40 x 40 cells of 1 m: two round hills on asphalt, sand on the east half (two grounds)."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    z = 3.0 * np.exp(-((x - 14) ** 2 + (y - 26) ** 2) / 60.0) + 2.0 * np.exp(-((x - 28) ** 2 + (y - 12) ** 2) / 40.0)
    ground = np.where(x > 20, 1, 0)
    return TerrainMap(z, 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})


@pytest.fixture(scope="module")
def hills_cost() -> EnergyCost:
    return with_interval(CostSpec().build(hills_map()))


def ridge_map() -> TerrainMap:
    """40 x 40 cells of 1 m of snow: a north-south ridge (y >= 10) whose west face (grade 0.25) snow cannot climb
    but can descend, and whose east face is gentle (grade 0.075); flat south of y = 10."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    prof = np.where(x < 12, 0.0, np.where(x < 18, 0.25 * (x - 12), np.maximum(1.5 - 0.075 * (x - 18), 0.0)))
    return TerrainMap(np.where(y >= 10, prof, 0.0), 1.0, ground=np.zeros((40, 40), int), ground_names={0: "snow"})


def exact_optimum(prices: PairPrices, budget_j: float, q: float, value: dict[int, float], *, depot: int = 0,
                  service_j: np.ndarray | None = None, on_time: Callable[[list[int]], bool] | None = None,
                  chargers: dict[int, int] | None = None, full_budget_j: float | None = None) -> float:
    """The best value of one robot's tour over every subset and order of the sites ``value`` (point -> value) and,
    with ``chargers`` (point -> visits), every insertion of charging stops, priced as the robot drives it: each
    segment between charges the legs joined (``prices.tour_interval``, the turns at the stops included) at its
    ``q`` quantile, service included, within its budget (the first ``budget_j``, after a charge ``full_budget_j``),
    ``on_time(sites so far)`` where given. A prefix priced above its budget prunes (its price only grows)."""
    service = np.zeros(len(prices)) if service_j is None else np.asarray(service_j, dtype=float)
    chargers = chargers or {}
    best = 0.0

    def fits(seg: list[int], came: int | None, limit: float) -> bool:
        return prices.tour_interval(seg, float(service[seg[1:]].sum()), arrived_from=came).quantile_j(q) <= limit

    def walk(seg: list[int], came: int | None, limit: float, sites: list[int], used: dict[int, int], got: float):
        nonlocal best
        if fits([*seg, depot], came, limit):
            best = max(best, got)
        for s in value:
            if s not in sites and fits([*seg, s], came, limit) and (on_time is None or on_time([*sites, s])):
                walk([*seg, s], came, limit, [*sites, s], used, got + value[s])
        for c, visits in chargers.items():
            if c != seg[-1] and used[c] < visits and fits([*seg, c], came, limit):
                walk([c], seg[-1], full_budget_j, sites, {**used, c: used[c] + 1}, got)

    walk([depot], None, budget_j, [], dict.fromkeys(chargers, 0), 0.0)
    return best


def exact_fleet_optimum(prices: PairPrices, budgets_j: list[float], q: float, value: dict[int, float], *,
                        depot: int = 0) -> float:
    """The best value of one or two robots' tours from one ``depot`` over every split of the sites ``value`` (point
    -> value) between them and every order, each tour priced as the robot drives it (``prices.tour_interval`` at its
    ``q`` quantile within its budget). A prefix priced above the largest budget prunes."""
    top = max(budgets_j)
    fits: dict[frozenset[int], float] = {}  # each set of sites some order visits: its least price at Q

    def walk(seq: list[int]) -> None:
        back = prices.tour_interval([*seq, depot]).quantile_j(q)
        key = frozenset(seq[1:])
        fits[key] = min(fits.get(key, float("inf")), back)
        for s in value:
            if s not in seq and prices.tour_interval([*seq, s]).quantile_j(q) <= top:
                walk([*seq, s])

    walk([depot])
    sets = list(fits.items())

    def worth(sites: frozenset[int]) -> float:
        return float(sum(value[s] for s in sites))

    if len(budgets_j) == 1:
        return max((worth(k) for k, e in sets if e <= budgets_j[0]), default=0.0)
    if len(budgets_j) != 2:
        raise ValueError("one or two robots")
    first = [k for k, e in sets if e <= budgets_j[0]]
    second = [k for k, e in sets if e <= budgets_j[1]]
    return max((worth(a) + worth(b) for a in first for b in second if not a & b), default=0.0)
