"""Reachability: the energy rasters from a depot (and back), the cells within a budget, their files and figures.

The answer of :func:`planner.reachability` (the rasters alone) and of
:func:`planner.reach_report.reach_on_battery` (the same, with the priced map's header and the battery:
what ``terrawatt reach`` prints and writes).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery
from energy.battery import S_PER_H
from terrain import TerrainMap
from terrain.geotiff import write_geotiff
from terrain.grid import Grid
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import atomic_open, check_output_path, remove_stale_temporaries
from terrawatt_base.errors import FileFormatError, InvalidParameterError, UnknownNameError
from terrawatt_base.formats import read_versioned_npz, result_document, write_result_json

from .reachability_plot import plot_reachability

__all__ = ["Reachability", "REACH_FORMAT_VERSION", "REACH_LAYERS"]

#: Format version of the ``.npz`` files :meth:`Reachability.write_raster` writes and :meth:`Reachability.load` reads.
REACH_FORMAT_VERSION = 1
_MAGIC = "terrawatt-reachability"
#: Rasters :meth:`Reachability.write_raster` can put in a GeoTIFF (``"energy"``: the one the budget applies to).
REACH_LAYERS = ("energy", "forward", "back", "round_trip", "reachable")


def _raster(name: str, value: Any, shape: tuple[int, int]) -> np.ndarray:
    """``value`` as a read-only float64 raster of ``shape`` (a read-only float64 array is kept, else copied)."""
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and not value.flags.writeable:
        arr = value
    else:
        arr = np.array(value, dtype=np.float64)
    if arr.shape != shape:
        raise InvalidParameterError(f"{name} must have the grid's shape {shape!r}, got {arr.shape!r}")
    if np.isnan(arr).any() or (arr < 0).any():
        raise InvalidParameterError(f"{name} must hold energies >= 0 (J) or inf, got NaN or a negative value")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Reachability:
    """The least energy (J) from a depot to every cell of a map, and back; the cells within a budget.

    Made by :func:`planner.reachability`. Rasters are indexed ``[row, col]`` on :attr:`grid`
    (row grows with y); ``inf`` marks a cell that cannot be reached (an obstacle, a cell
    steeper than the slope limit, or one cut off from the depot).

    Attributes
    ----------
    grid : terrain.grid.Grid
        The cost's grid.
    crs : str or None
        The map's coordinate reference system (kept for GeoTIFF output).
    depot_xy_m : (float, float)
        The depot (m).
    forward_energy_j : ndarray, shape (rows, cols)
        Least drive energy from the depot to each cell centre (J).
    back_energy_j, round_trip_energy_j : ndarray or None
        Least energy from each cell back to the depot, and ``forward + back`` (J);
        ``None`` unless ``round_trip``.
    blocked : ndarray of bool
        Obstacle cells and cells steeper than the slope limit.
    budget_j : float or None
        Battery energy available at the depot (J); ``None``: no budget, every reachable
        cell counts.
    reserve_j : float
        Energy that must remain at the end (J), ``0 <= reserve_j < budget_j``.
    round_trip : bool
        Whether the budget applies to the round trip (else to the way out).
    graph_time_s, search_time_s : float
        Seconds spent costing the lattice moves (0 when cached on the cost) and searching.
    priced : planner.cost_spec.PricedMap or None
        The header of a reach on a battery (:func:`planner.reach_report.reach_on_battery`): the map
        and how it was priced, with the times (its kernels' compile time includes the reachability
        kernels'); None for :func:`planner.reachability` alone.
    battery : Battery or None
        The battery of the budget (capacity, voltage, reserve), with ``priced``.
    total_time_s : float
        Seconds to price the map and search, with ``priced`` (else NaN).
    """

    grid: Grid
    crs: str | None
    depot_xy_m: tuple[float, float]
    forward_energy_j: np.ndarray
    back_energy_j: np.ndarray | None
    round_trip_energy_j: np.ndarray | None
    blocked: np.ndarray
    budget_j: float | None
    reserve_j: float
    round_trip: bool
    graph_time_s: float = 0.0
    search_time_s: float = 0.0
    priced: Any = field(default=None, repr=False)  # a PricedMap: its module prices maps, which needs this one
    battery: Battery | None = None
    total_time_s: float = math.nan

    def __post_init__(self) -> None:
        if (self.priced is None) != (self.battery is None):
            raise InvalidParameterError("priced and battery come together (the header of a reach on a battery)")
        if not isinstance(self.grid, Grid):
            raise InvalidParameterError(f"grid must be a terrain Grid, got {type(self.grid).__name__!r}")
        shape = self.grid.shape
        object.__setattr__(self, "forward_energy_j", _raster("forward_energy_j", self.forward_energy_j, shape))
        if self.round_trip != (self.back_energy_j is not None and self.round_trip_energy_j is not None):
            raise InvalidParameterError(
                f"round_trip={self.round_trip!r} needs back_energy_j and round_trip_energy_j (and only then)"
            )
        if self.round_trip:
            object.__setattr__(self, "back_energy_j", _raster("back_energy_j", self.back_energy_j, shape))
            object.__setattr__(self, "round_trip_energy_j",
                               _raster("round_trip_energy_j", self.round_trip_energy_j, shape))
        blocked = np.array(self.blocked, dtype=bool)
        if blocked.shape != shape:
            raise InvalidParameterError(f"blocked must have the grid's shape {shape!r}, got {blocked.shape!r}")
        blocked.setflags(write=False)
        object.__setattr__(self, "blocked", blocked)
        if self.budget_j is not None and not (math.isfinite(self.budget_j) and self.budget_j > 0):
            raise InvalidParameterError(f"budget_j must be None or a finite energy > 0 (J), got {self.budget_j!r}")
        budget = math.inf if self.budget_j is None else self.budget_j
        if not (math.isfinite(self.reserve_j) and 0.0 <= self.reserve_j < budget):
            raise InvalidParameterError(
                f"reserve_j must be a finite energy in [0, budget_j) (J), got {self.reserve_j!r} "
                f"with budget_j={self.budget_j!r}"
            )

    # ------------------------------------------------------------------ figures
    @property
    def energy_j(self) -> np.ndarray:
        """The raster the budget applies to: round-trip energies if :attr:`round_trip`, else forward (J)."""
        return self.round_trip_energy_j if self.round_trip_energy_j is not None else self.forward_energy_j

    @property
    def usable_energy_j(self) -> float:
        """``budget_j - reserve_j`` (J); ``inf`` without a budget."""
        return math.inf if self.budget_j is None else self.budget_j - self.reserve_j

    @cached_property
    def reachable(self) -> np.ndarray:
        """Cells whose :attr:`energy_j` is finite and at most :attr:`usable_energy_j` (read-only bool raster)."""
        e = self.energy_j
        mask = np.isfinite(e) & (e <= self.usable_energy_j)
        mask.setflags(write=False)
        return mask

    @cached_property
    def n_reachable_cells(self) -> int:
        """Number of reachable cells."""
        return int(np.count_nonzero(self.reachable))

    @property
    def reachable_area_m2(self) -> float:
        """Area of the reachable cells (m^2)."""
        return self.n_reachable_cells * self.grid.cell_size_m**2

    @property
    def reachable_fraction(self) -> float:
        """Reachable cells over free (not blocked) cells; 0 when every cell is blocked."""
        free = int(self.blocked.size - np.count_nonzero(self.blocked))
        return self.n_reachable_cells / free if free else 0.0

    @cached_property
    def farthest_reachable_m(self) -> float:
        """Largest straight-line distance from the depot to a reachable cell centre (m); NaN if none."""
        rows, cols = np.nonzero(self.reachable)
        if rows.size == 0:
            return math.nan
        x, y = self.grid.xy(rows, cols)
        return float(np.max(np.hypot(np.asarray(x) - self.depot_xy_m[0], np.asarray(y) - self.depot_xy_m[1])))

    def _max_over_reachable(self, raster: np.ndarray | None) -> float:
        if raster is None or self.n_reachable_cells == 0:
            return math.nan
        return float(np.max(raster[self.reachable]))

    @property
    def max_forward_energy_j(self) -> float:
        """Largest forward energy over the reachable cells (J); NaN if none."""
        return self._max_over_reachable(self.forward_energy_j)

    @property
    def max_round_trip_energy_j(self) -> float:
        """Largest round-trip energy over the reachable cells (J); NaN if none or not a round trip."""
        return self._max_over_reachable(self.round_trip_energy_j)

    @property
    def terrain(self) -> TerrainMap | None:
        """The map of a reach on a battery (None without the header)."""
        return None if self.priced is None else self.priced.terrain

    @property
    def model(self) -> Any:
        """The saved model that priced the edges (a :class:`planner.cost_spec.PlanModel`); None for the physics
        presets or without the header."""
        return None if self.priced is None else self.priced.model

    def to_dict(self, raster: str | None = None) -> dict[str, Any]:
        """The scalar figures as a JSON-ready result document, format ``terrawatt-reachability`` (energies in J and Wh;
        NaN left for the writer, :func:`terrawatt_base.formats.write_result_json`): reach.json.

        With the header of a reach on a battery, the map, how it was priced, the battery, the
        times and ``raster`` (the raster file's name) come first, the saved model (if one priced
        the edges) last.
        """

        def wh(x: float | None) -> float | None:
            return None if x is None else x / S_PER_H

        header: dict[str, Any] = {}
        priced, b = self.priced, self.battery
        if priced is not None and b is not None:
            header = {"map": priced.map_label, **priced.fields(), "battery_ah": b.capacity_ah,
                      "battery_voltage_v": b.voltage_v, "reserve_pct": b.min_reserve_pct,
                      "map_preparation_s": priced.map_preparation_s, "total_time_s": self.total_time_s,
                      "kernel_compile_s": priced.kernel_compile_s, "raster": raster}
        rows, cols = self.grid.shape
        document = result_document("reachability", REACH_FORMAT_VERSION, {
            **header,
            "depot_xy_m": list(self.depot_xy_m),
            "round_trip": self.round_trip,
            "budget_j": self.budget_j,
            "budget_wh": wh(self.budget_j),
            "reserve_j": self.reserve_j,
            "reserve_wh": wh(self.reserve_j),
            "usable_energy_j": None if self.budget_j is None else self.usable_energy_j,
            "usable_energy_wh": None if self.budget_j is None else wh(self.usable_energy_j),
            "reachable_cells": self.n_reachable_cells,
            "reachable_area_m2": self.reachable_area_m2,
            "reachable_fraction_of_free": self.reachable_fraction,
            "farthest_reachable_m": self.farthest_reachable_m,
            "max_forward_energy_j": self.max_forward_energy_j,
            "max_forward_energy_wh": wh(self.max_forward_energy_j),
            "max_round_trip_energy_j": self.max_round_trip_energy_j,
            "max_round_trip_energy_wh": wh(self.max_round_trip_energy_j),
            "grid": {"rows": rows, "cols": cols, "cell_size_m": self.grid.cell_size_m,
                     "origin_xy_m": list(self.grid.origin_xy_m), "crs": self.crs},
            "graph_time_s": self.graph_time_s,
            "search_time_s": self.search_time_s,
        })
        if self.model is not None:  # files priced by the presets stay as they were
            m = self.model.to_dict()
            document["model"] = {k: m[k] for k in ("file", "class", "model_ground", "grounds")}
        return document

    def summary(self) -> str:
        """What ``terrawatt reach`` prints: the map, robot and battery (with the header), then the reachable area and
        the times."""
        priced, b, grid = self.priced, self.battery, self.grid

        def wh(j: float) -> str:
            return "-" if math.isnan(j) else f"{j / S_PER_H:.2f} Wh"

        lines = []
        if priced is not None and b is not None:
            budget_wh = self.budget_j / S_PER_H if self.budget_j is not None else math.nan
            lines = [
                f"map: {priced.map_label}  {grid.shape[0]} x {grid.shape[1]} cells of {grid.cell_size_m:g} m",
                priced.robot_line(),
                f"battery {b.capacity_ah:g} Ah at {b.voltage_v:g} V = {budget_wh:.1f} Wh; reserve "
                f"{b.min_reserve_pct:g} % -> {self.usable_energy_j / S_PER_H:.1f} Wh usable "
                f"{'there and back' if self.round_trip else 'one way'}",
                f"depot {self.depot_xy_m}",
                "",
            ]
        farthest = self.farthest_reachable_m
        rows = [
            ("reachable area", f"{self.reachable_area_m2:,.0f} m^2 ({100 * self.reachable_fraction:.1f} % of free "
                               "cells)"),
            ("reachable cells", f"{self.n_reachable_cells:,}"),
            ("farthest reachable", "-" if math.isnan(farthest) else f"{farthest:,.1f} m"),
            ("max one-way energy", wh(self.max_forward_energy_j)),
        ]
        if self.round_trip:
            rows.append(("max round-trip energy", wh(self.max_round_trip_energy_j)))
        if priced is not None:
            rows.append(("map preparation", f"{priced.map_preparation_s:.2f} s"))
        rows += [("lattice moves", f"{self.graph_time_s:.2f} s"), ("search", f"{self.search_time_s:.2f} s")]
        if priced is not None:
            rows.append(("total", f"{self.total_time_s:.2f} s"))
        lines += [f"{name:<24} {value}" for name, value in rows]
        if not self.n_reachable_cells:
            lines += ["", "no cell is reachable within the usable energy: a larger battery or a smaller reserve"]
        if priced is not None and priced.kernel_compile_s > 1.0:
            lines.append(f"(compiled the kernels in {priced.kernel_compile_s:.1f} s: first run in this environment; "
                         "not in the times above)")
        return "\n".join(lines)

    def layer(self, name: str) -> np.ndarray:
        """One raster by name, one of :data:`REACH_LAYERS` (``"reachable"`` as 0/1 uint8).

        Raises
        ------
        UnknownNameError
            Another name, or ``"back"`` / ``"round_trip"`` of a one-way result.
        """
        if name not in REACH_LAYERS:
            raise UnknownNameError(f"layer must be one of {REACH_LAYERS!r}, got {name!r}")
        if name == "reachable":
            return self.reachable.astype(np.uint8)
        value = {"energy": self.energy_j, "forward": self.forward_energy_j, "back": self.back_energy_j,
                 "round_trip": self.round_trip_energy_j}[name]
        if value is None:
            raise UnknownNameError(f"layer {name!r} exists only for a round trip (reachability(..., round_trip=True))")
        return value

    # ------------------------------------------------------------------ files
    def write(self, out_dir: str | os.PathLike[str], *, raster: str | None = None,
              on_figure_error: str = "warn") -> list[Path]:
        """Write the raster (``raster``: ``reach.tif`` or ``reach.npz``; default ``reach.tif`` when the map has a
        CRS, else ``reach.npz``), reach.json and reach.png into ``out_dir``; return the files written.

        A figure that fails warns and is left out (:func:`terrawatt_base.answer.write_answer`).
        """
        name = raster if raster is not None else ("reach.tif" if self.crs else "reach.npz")
        label = "a map" if self.priced is None else self.priced.map_label
        return write_answer(out_dir, {name: self.write_raster,
                                      "reach.json": lambda p: write_result_json(p, self.to_dict(Path(name).name))},
                            {"reach.png": lambda p: self.plot(p, title=f"terrawatt: energy reachability on {label}")},
                            on_figure_error=on_figure_error)

    def write_raster(self, path: str | os.PathLike[str], *, layer: str = "energy") -> Path:
        """Write the rasters atomically: a ``.npz`` file (every raster and figure, versioned) or a GeoTIFF.

        A ``.tif`` / ``.tiff`` path gets one band, ``layer`` (default: :attr:`energy_j`, in J,
        ``inf`` where unreachable), north-up in the map's CRS (needs the ``geo`` extra,
        rasterio). A ``.npz`` path gets all rasters and the budget; read it back with
        :meth:`load`.

        Raises
        ------
        InvalidParameterError
            Another suffix, or a path that is a folder.
        UnknownNameError
            An unknown ``layer`` (GeoTIFF only).
        """
        target = check_output_path(path, "path")
        suffix = target.suffix.lower()
        if suffix in (".tif", ".tiff"):
            raster = self.layer(layer)
            tmap = TerrainMap(np.zeros(self.grid.shape), self.grid.cell_size_m, self.grid.origin_xy_m, crs=self.crs)
            tmap[f"reach_{layer}"] = raster
            return write_geotiff(tmap, target, layer=f"reach_{layer}")
        if suffix != ".npz":
            raise InvalidParameterError(f"reachability files end in '.npz', '.tif' or '.tiff', got {str(target)!r}")
        payload: dict[str, np.ndarray] = {
            "__magic__": np.array(_MAGIC),
            "__version__": np.array(REACH_FORMAT_VERSION),
            "cell_size_m": np.array(self.grid.cell_size_m),
            "origin_xy_m": np.array(self.grid.origin_xy_m),
            "crs": np.array("" if self.crs is None else self.crs),
            "depot_xy_m": np.array(self.depot_xy_m),
            "budget_j": np.array(math.nan if self.budget_j is None else self.budget_j),
            "reserve_j": np.array(self.reserve_j),
            "round_trip": np.array(self.round_trip),
            "forward_energy_j": self.forward_energy_j,
            "blocked": self.blocked,
            "graph_time_s": np.array(self.graph_time_s),
            "search_time_s": np.array(self.search_time_s),
        }
        if self.round_trip:
            payload["back_energy_j"] = self.back_energy_j
            payload["round_trip_energy_j"] = self.round_trip_energy_j
        with atomic_open(target, "wb") as fh:
            np.savez_compressed(fh, **payload)
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Reachability:
        """Read a ``.npz`` file written by :meth:`write_raster`.

        Raises
        ------
        FileFormatError
            Missing, corrupt or foreign file, or missing entries.
        FormatVersionError
            Another format version.
        """
        p = Path(path)
        remove_stale_temporaries(p)
        c = read_versioned_npz(p, magic=_MAGIC, version=REACH_FORMAT_VERSION, what="reachability")
        try:
            forward = c["forward_energy_j"]
            budget = float(c["budget_j"])
            round_trip = bool(c["round_trip"])
            return cls(
                grid=Grid(tuple(forward.shape), float(c["cell_size_m"]), tuple(c["origin_xy_m"].tolist())),
                crs=str(c["crs"]) or None,
                depot_xy_m=tuple(c["depot_xy_m"].tolist()),
                forward_energy_j=forward,
                back_energy_j=c["back_energy_j"] if round_trip else None,
                round_trip_energy_j=c["round_trip_energy_j"] if round_trip else None,
                blocked=c["blocked"],
                budget_j=None if math.isnan(budget) else budget,
                reserve_j=float(c["reserve_j"]),
                round_trip=round_trip,
                graph_time_s=float(c["graph_time_s"]),
                search_time_s=float(c["search_time_s"]),
            )
        except KeyError as exc:
            raise FileFormatError(f"reachability file {str(p)!r} lacks entry {exc.args[0]!r}") from exc
        except (TypeError, ValueError) as exc:
            raise FileFormatError(f"reachability file {str(p)!r} has malformed content: {exc}") from exc

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None, title: str | None = None,
             dpi: int = 130) -> Path | Any:
        """Draw the energy field (Wh, with contours), the reachable area outlined, the depot and
        the blocked cells (:func:`planner.reachability_plot.plot_reachability`).

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax``
        (draw into these matplotlib axes, write nothing and return them).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or ``ax``.
        """
        return plot_reachability(self, path, ax=ax, title=title, dpi=dpi)

    def __repr__(self) -> str:
        return (
            f"Reachability(shape={self.grid.shape}, depot_xy_m={self.depot_xy_m}, round_trip={self.round_trip}, "
            f"budget_j={self.budget_j!r}, reachable_area_m2={self.reachable_area_m2:.1f})"
        )
