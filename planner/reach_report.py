"""Reachability on one battery: the map priced as a spec says, the cells a battery reaches, with its header.

The answer is a :class:`planner.reachability_result.Reachability` carrying the priced map and the battery:
its ``summary()`` is what ``terrawatt reach`` prints, its ``write(out_dir)`` the raster, reach.json and reach.png.
"""

from __future__ import annotations

import dataclasses
import time

from energy import Battery
from energy.battery import S_PER_H
from terrain import TerrainMap
from terrawatt_base.checks import check_instance

from .cost_spec import CostSpec
from .reachability import reachability, warm_up_reachability
from .reachability_result import Reachability

__all__ = ["reach_on_battery"]


def reach_on_battery(
    terrain: TerrainMap,
    depot_xy_m: tuple[float, float],
    *,
    battery: Battery,
    round_trip: bool = False,
    pricing: CostSpec | None = None,
    map_label: str = "map",
) -> Reachability:
    """The cells a battery reaches from a depot (:func:`planner.reachability`), with the priced map, the battery and
    the timings (the header :class:`~planner.reachability_result.Reachability` carries).

    The budget is the full battery's energy (capacity times voltage, in J; its initial charge is not
    used), the reserve its ``min_reserve_pct`` % of it.

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    depot_xy_m : (float, float)
        The depot (m).
    battery : Battery
        Capacity, voltage and reserve (e.g. :func:`planner.missions.mission_report.mission_battery`: a capacity at
        the robot's voltage).
    round_trip : bool
        Budget the way there and back.
    pricing : CostSpec, optional
        How the edges are priced (:class:`planner.cost_spec.CostSpec`, default ``CostSpec()``; its
        ``risk`` is not used: the reach is at the mean).
    map_label : str
        How the map is named.

    Returns
    -------
    Reachability
        With ``priced``, ``battery`` and ``total_time_s``.

    Raises
    ------
    InvalidParameterError
        Not a Battery.
    TerrawattError
        As :meth:`planner.cost_spec.CostSpec.build` and :func:`planner.reachability`.

    Examples
    --------
    >>> from terrain import flat_map
    >>> from energy import Battery
    >>> report = reach_on_battery(flat_map((20, 20), 1.0, ground="asphalt"), (10.0, 10.0), battery=Battery(0.01, 24.0))
    >>> report.n_reachable_cells > 0, report.battery.usable_energy_wh
    (True, 0.192)
    """
    battery = check_instance("battery", battery, Battery)
    pricing = CostSpec.given(pricing)
    budget_j = battery.capacity_ah * battery.voltage_v * S_PER_H
    reach_compile_s = warm_up_reachability()
    priced = dataclasses.replace(pricing, risk=None).price(terrain, map_label=map_label)  # the reach is at the mean
    priced = dataclasses.replace(priced, kernel_compile_s=priced.kernel_compile_s + reach_compile_s)
    t1 = time.perf_counter()
    reach = reachability(priced.cost, depot_xy_m, budget_j=budget_j, reserve_j=budget_j * battery.min_reserve_pct / 100.0,
                         round_trip=round_trip)
    total_s = priced.map_preparation_s + time.perf_counter() - t1
    return dataclasses.replace(reach, priced=priced, battery=battery, total_time_s=total_s)
