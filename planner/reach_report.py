"""Reachability on one battery, reported: the printed figures, reach.json, the raster and the figure (ReachReport)."""

from __future__ import annotations

import dataclasses
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from energy import Battery
from energy.battery import S_PER_H
from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.figure_file import draw_figure
from terrawatt_base.formats import result_document, write_result_json

from .cost_spec import CostSpec, PlanModel, PricedMap
from .reachability import reachability, warm_up_reachability
from .reachability_result import Reachability

__all__ = ["ReachReport", "reach_on_battery"]


@dataclass(frozen=True)
class ReachReport:
    """The least energy from a depot to every cell (and back) within a battery, ready to print and write.

    Made by :func:`reach_on_battery`. :meth:`summary` is the text ``terrawatt reach`` prints,
    :meth:`to_dict` the content of reach.json, :meth:`write` writes the raster, reach.json and
    reach.png.

    Attributes
    ----------
    reach : Reachability
        The energy rasters, the budget and the reachable cells.
    priced : PricedMap
        The map and how it was priced, with the times (its map preparation; the kernels' compile
        time includes the reachability kernels').
    battery : Battery
        The battery: capacity (Ah), voltage (V), share kept in reserve (%).
    total_time_s : float
        Seconds to price the map and search.
    """

    reach: Reachability
    priced: PricedMap = field(repr=False, compare=False)
    battery: Battery
    total_time_s: float

    @property
    def terrain(self) -> TerrainMap:
        """The map."""
        return self.priced.terrain

    @property
    def model(self) -> PlanModel | None:
        """The saved model that priced the edges, or None for the physics presets."""
        return self.priced.model

    def summary(self) -> str:
        """What ``terrawatt reach`` prints: the map, robot and battery, then the reachable area and the times."""
        reach, t, priced, b = self.reach, self.terrain, self.priced, self.battery

        def wh(j: float) -> str:
            return "-" if math.isnan(j) else f"{j / S_PER_H:.2f} Wh"

        budget_wh = reach.budget_j / S_PER_H if reach.budget_j is not None else math.nan
        lines = [
            f"map: {priced.map_label}  {t.shape[0]} x {t.shape[1]} cells of {t.cell_size_m:g} m",
            priced.robot_line(),
            f"battery {b.capacity_ah:g} Ah at {b.voltage_v:g} V = {budget_wh:.1f} Wh; reserve {b.min_reserve_pct:g} "
            f"% -> {reach.usable_energy_j / S_PER_H:.1f} Wh usable {'there and back' if reach.round_trip else 'one way'}",
            f"depot {reach.depot_xy_m}",
            "",
        ]
        farthest = reach.farthest_reachable_m
        rows = [
            ("reachable area", f"{reach.reachable_area_m2:,.0f} m^2 ({100 * reach.reachable_fraction:.1f} % of free "
                               "cells)"),
            ("reachable cells", f"{reach.n_reachable_cells:,}"),
            ("farthest reachable", "-" if math.isnan(farthest) else f"{farthest:,.1f} m"),
            ("max one-way energy", wh(reach.max_forward_energy_j)),
        ]
        if reach.round_trip:
            rows.append(("max round-trip energy", wh(reach.max_round_trip_energy_j)))
        rows += [("map preparation", f"{priced.map_preparation_s:.2f} s"), ("lattice moves", f"{reach.graph_time_s:.2f} s"),
                 ("search", f"{reach.search_time_s:.2f} s"), ("total", f"{self.total_time_s:.2f} s")]
        lines += [f"{name:<24} {value}" for name, value in rows]
        if not reach.n_reachable_cells:
            lines += ["", "no cell is reachable within the usable energy: a larger battery or a smaller reserve"]
        if priced.kernel_compile_s > 1.0:
            lines.append(f"(compiled the kernels in {priced.kernel_compile_s:.1f} s: first run in this environment; not "
                         "in the times above)")
        return "\n".join(lines)

    def to_dict(self, raster: str | None = None) -> dict[str, Any]:
        """The content of reach.json: a ``terrawatt-reachability`` result document (:meth:`Reachability.to_dict`)
        with the query, the battery, the times and ``raster`` (the raster file's name)."""
        reach = self.reach.to_dict()
        result = result_document("reachability", reach.pop("format_version"), {
            "map": self.priced.map_label,
            **self.priced.fields(),
            "battery_ah": self.battery.capacity_ah,
            "battery_voltage_v": self.battery.voltage_v,
            "reserve_pct": self.battery.min_reserve_pct,
            "map_preparation_s": self.priced.map_preparation_s,
            "total_time_s": self.total_time_s,
            "kernel_compile_s": self.priced.kernel_compile_s,
            "raster": raster,
            **{k: v for k, v in reach.items() if k != "format"},
        })
        if self.model is not None:  # files priced by the presets stay as they were
            m = self.model.to_dict()
            result["model"] = {k: m[k] for k in ("file", "class", "model_ground", "grounds")}
        return result

    def write(self, out_dir: str | os.PathLike[str], *, raster: str | None = None,
              on_figure_error: str = "warn") -> list[Path]:
        """Write the raster (``raster``: ``reach.tif`` or ``reach.npz``; default ``reach.tif`` when the map has a
        CRS, else ``reach.npz``), reach.json and reach.png into ``out_dir``; return the files written.

        A figure that fails warns and is left out (:func:`terrawatt_base.figure_file.draw_figure`).
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        name = raster if raster is not None else ("reach.tif" if self.terrain.crs else "reach.npz")
        written = [self.reach.write(out / name)]
        written.append(write_result_json(out / "reach.json", self.to_dict(written[0].name)))
        png = draw_figure(out / "reach.png", lambda: self.reach.plot(
            out / "reach.png", title=f"terrawatt: energy reachability on {self.priced.map_label}"),
            on_error=on_figure_error)
        return written + ([png] if png is not None else [])


def reach_on_battery(
    terrain: TerrainMap,
    depot_xy_m: tuple[float, float],
    *,
    battery: Battery,
    round_trip: bool = False,
    pricing: CostSpec | None = None,
    map_label: str = "map",
) -> ReachReport:
    """The cells a battery reaches from a depot (:func:`planner.reachability`), with its budget and timings.

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
    ReachReport

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
    >>> report.reach.n_reachable_cells > 0, report.battery.usable_energy_wh
    (True, 0.192)
    """
    battery = check_instance("battery", battery, Battery)
    pricing = CostSpec() if pricing is None else check_instance("pricing", pricing, CostSpec)
    budget_j = battery.capacity_ah * battery.voltage_v * S_PER_H
    reach_compile_s = warm_up_reachability()
    priced = dataclasses.replace(pricing, risk=None).price(terrain, map_label=map_label)  # the reach is at the mean
    priced = dataclasses.replace(priced, kernel_compile_s=priced.kernel_compile_s + reach_compile_s)
    t1 = time.perf_counter()
    reach = reachability(priced.cost, depot_xy_m, budget_j=budget_j, reserve_j=budget_j * battery.min_reserve_pct / 100.0,
                         round_trip=round_trip)
    total_s = priced.map_preparation_s + time.perf_counter() - t1
    return ReachReport(reach=reach, priced=priced, battery=battery, total_time_s=total_s)
