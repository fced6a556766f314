"""The sites of a tour (name, place, value, service, time window) and the robots that visit them (battery, depot)."""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery
from terrain import TerrainMap
from terrain.georef import lonlat_to_xy
from terrawatt_base.checks import check_real, readonly, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from ..batch_pairs import read_sites_csv
from ..edge_cost import EnergyCost

__all__ = ["TourSites", "TourRobot", "read_tour_sites_csv", "SITE_VALUE_COLUMNS", "SITE_WINDOW_COLUMNS"]

#: Optional columns of a tour's sites CSV beside the batch command's (default 1, 0 and 0).
SITE_VALUE_COLUMNS = ("value", "service_energy_j", "service_time_s")
#: Optional columns of a site's time window (s from the robots' departure; both or neither; empty: no window).
SITE_WINDOW_COLUMNS = ("tw_start_s", "tw_end_s")


def _per_site(name: str, value: Any, n: int, default: float) -> np.ndarray:
    if value is None:
        return readonly(np.full(n, default))
    arr = real_array(name, value, finite=True).ravel() if np.ndim(value) else np.full(n, float(value))
    if arr.shape != (n,):
        raise InvalidParameterError(f"{name} must hold one number per site ({n}), got shape {arr.shape!r}")
    if np.any(arr < 0):
        k = int(np.flatnonzero(arr < 0)[0])
        raise InvalidParameterError(f"{name} must be >= 0 for every site; site {k} has {float(arr[k])!r}")
    return readonly(arr.astype(float))


def _windows(value: Any, names: tuple[str, ...]) -> np.ndarray:
    """Each site's ``(earliest_s, latest_s)``; ``(0, inf)`` where it has none."""
    n = len(names)
    out = np.tile([0.0, math.inf], (n, 1))
    if value is None:
        return readonly(out)
    rows = list(value) if not isinstance(value, np.ndarray) else list(value.reshape(-1, 2)) if value.size else []
    if len(rows) != n:
        raise InvalidParameterError(f"time_window_s must hold one (earliest_s, latest_s) or None per site ({n}), "
                                    f"got {len(rows)} entries")
    for k, w in enumerate(rows):
        if w is None:
            continue
        try:
            early, late = (float(v) for v in w)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"time_window_s of site {names[k]!r} must be (earliest_s, latest_s) or None, "
                                        f"got {w!r}") from None
        if early == 0.0 and late == math.inf:  # what a site without a window holds: none
            continue
        if not (math.isfinite(early) and math.isfinite(late)) or not 0.0 <= early <= late:
            raise InvalidParameterError(f"time_window_s of site {names[k]!r} must be finite with 0 <= earliest_s <= "
                                        f"latest_s (s from the departure), got ({early!r}, {late!r})")
        out[k] = early, late
    return readonly(out)


@dataclass(frozen=True, eq=False)
class TourSites:
    """The sites a tour may visit.

    Attributes
    ----------
    names : tuple of str
        A unique, non-empty name per site (what the result calls it).
    xy_m : ndarray, shape (N, 2)
        Places (m, the map's metres; :meth:`from_lonlat` for degrees).
    value : ndarray, shape (N,)
        What visiting the site is worth (>= 0; default 1 each): the tour maximises its sum.
    service_energy_j, service_time_s : ndarray, shape (N,)
        Energy (J) and time (s) spent at the site (>= 0; default 0).
    time_window_s : ndarray, shape (N, 2)
        When service may start at each site, ``(earliest_s, latest_s)`` in seconds from the robots'
        departure; given as one pair or ``None`` (no window) per site, or ``None`` for no windows at all.
        A site without a window holds (and may be given) ``(0, inf)``. A robot arriving early waits
        until ``earliest_s``; one that cannot arrive by ``latest_s`` cannot visit the site.

    Raises
    ------
    InvalidParameterError
        No sites; repeated or empty names; NaN places; negative values or service; a window that is not
        finite or not ``0 <= earliest_s <= latest_s`` (the site named).

    Examples
    --------
    >>> s = TourSites(("a", "b"), [[1.0, 2.0], [3.0, 4.0]], value=[2.0, 1.0])
    >>> len(s), s.value.tolist()
    (2, [2.0, 1.0])
    """

    names: tuple[str, ...]
    xy_m: Any
    value: Any = None
    service_energy_j: Any = None
    service_time_s: Any = None
    time_window_s: Any = None

    def __post_init__(self) -> None:
        xy = real_array("xy_m", self.xy_m, finite=True)
        if xy.ndim != 2 or xy.shape[1] != 2 or xy.shape[0] == 0:
            raise InvalidParameterError(f"xy_m must have shape (N, 2) with N >= 1 sites, got shape {xy.shape!r}")
        n = xy.shape[0]
        names = tuple(self.names)
        if len(names) != n or not all(isinstance(s, str) and s for s in names):
            raise InvalidParameterError(f"names must be {n} non-empty strings, one per site, got {names!r:.120}")
        if len(set(names)) != n:
            dup = next(s for s in names if names.count(s) > 1)
            raise InvalidParameterError(f"site names must be unique; {dup!r} appears {names.count(dup)} times")
        set_ = object.__setattr__
        set_(self, "names", names)
        set_(self, "xy_m", readonly(xy))
        set_(self, "value", _per_site("value", self.value, n, 1.0))
        set_(self, "service_energy_j", _per_site("service_energy_j", self.service_energy_j, n, 0.0))
        set_(self, "service_time_s", _per_site("service_time_s", self.service_time_s, n, 0.0))
        set_(self, "time_window_s", _windows(self.time_window_s, names))

    def __len__(self) -> int:
        return len(self.names)

    @property
    def has_windows(self) -> bool:
        """Whether any site has a time window."""
        w = self.time_window_s
        return bool(np.any(w[:, 0] > 0) or np.any(np.isfinite(w[:, 1])))

    @classmethod
    def from_lonlat(cls, names: Any, lonlat: Any, where: TerrainMap, **per_site: Any) -> TourSites:
        """Sites given as WGS 84 longitude, latitude (degrees), placed on the georeferenced map ``where``.

        No bounds check: a site off the map is its error row (:meth:`check_on`)."""
        arr = real_array("lonlat", lonlat, finite=True)
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise InvalidParameterError(f"lonlat must have shape (N, 2), got shape {arr.shape!r}")
        if not isinstance(where, TerrainMap) or where.crs is None:
            raise InvalidParameterError("sites in longitude / latitude need where=<a georeferenced TerrainMap> "
                                        "(a map with a CRS) to place them")
        x, y = lonlat_to_xy(arr[:, 0], arr[:, 1], where.crs)
        return cls(tuple(names), np.column_stack([x, y]), **per_site)

    def check_on(self, cost: EnergyCost) -> dict[str, str]:
        """The sites that cannot be visited on ``cost``'s map, each with why (off the map, on a blocked cell).

        Returns
        -------
        dict of str to str
            Site name -> reason; the sites not named are kept.
        """
        x, y = self.xy_m[:, 0], self.xy_m[:, 1]
        inside = np.asarray(cost.terrain.contains(x, y), dtype=bool)
        errors: dict[str, str] = {}
        for k in np.flatnonzero(~inside).tolist():
            errors[self.names[k]] = (f"off the map: ({x[k]:.6g}, {y[k]:.6g}) m lies outside the map bounds "
                                     f"{tuple(round(b, 6) for b in cost.terrain.bounds)!r}")
        idx = np.flatnonzero(inside)
        if idx.size:
            r, c = cost.terrain.rowcol(x[idx], y[idx])
            for k in idx[np.asarray(cost.blocked)[r, c]].tolist():
                errors[self.names[k]] = (f"on an obstacle: ({x[k]:.6g}, {y[k]:.6g}) m lies on a blocked cell "
                                         "(an obstacle or a slope above the limit)")
        return errors


@dataclass(frozen=True)
class TourRobot:
    """A robot of the fleet: its battery (with its reserve and initial charge) and its depot.

    Attributes
    ----------
    battery : Battery
        The pack; a tour may spend ``(initial_soc - reserve_soc) * energy_capacity_j`` at risk level Q.
    depot_xy_m : (float, float)
        Where its tour starts and ends (m).
    name : str
        How the result calls it.
    max_duration_s : float, optional
        The longest its tour may last, from leaving the depot at 0 to being back (s; driving, waiting and
        service); ``None``: no limit.

    Examples
    --------
    >>> r = TourRobot(Battery(10.0, 24.0, min_reserve_pct=20.0), (5.0, 5.0))
    >>> round(r.budget_j)
    691200
    """

    battery: Battery
    depot_xy_m: tuple[float, float]
    name: str = "robot 0"
    max_duration_s: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.battery, Battery):
            raise InvalidParameterError(f"battery must be an energy.Battery, got {type(self.battery).__name__!r}")
        xy = real_array("depot_xy_m", self.depot_xy_m, finite=True).ravel()
        if xy.shape != (2,):
            raise InvalidParameterError(f"depot_xy_m must be two finite coordinates (m), got {xy.tolist()!r}")
        if not isinstance(self.name, str) or not self.name:
            raise InvalidParameterError(f"name must be a non-empty string, got {self.name!r}")
        object.__setattr__(self, "depot_xy_m", (float(xy[0]), float(xy[1])))
        if self.max_duration_s is not None:
            object.__setattr__(self, "max_duration_s", check_real("max_duration_s", self.max_duration_s, low=0.0,
                                                                  low_inclusive=False))

    @property
    def budget_j(self) -> float:
        """Energy the tour may spend above the reserve (J): ``(initial_soc - reserve_soc) * capacity``."""
        b = self.battery
        return max(b.initial_soc - b.reserve_soc, 0.0) * b.energy_capacity_j

    def soc_after(self, energy_j: Any) -> np.ndarray:
        """State of charge (fraction) after spending ``energy_j`` from the initial charge (no losses)."""
        return self.battery.initial_soc - np.asarray(energy_j, dtype=float) / self.battery.energy_capacity_j


def read_tour_sites_csv(path: str | os.PathLike[str], where: TerrainMap | None = None) -> TourSites:
    """Tour sites from the batch command's sites CSV (``name, x_m, y_m`` or ``name, lon, lat``) with the
    optional columns :data:`SITE_VALUE_COLUMNS` (``value`` default 1, service energy J and time s default 0)
    and :data:`SITE_WINDOW_COLUMNS` (``tw_start_s``, ``tw_end_s``: both columns or neither; both cells
    empty: no window for that site).

    Raises
    ------
    FileNotFoundError, FileFormatError, DataError, InvalidParameterError
        As :func:`planner.batch_pairs.read_sites_csv`; a value that is not a number (the line and column
        named); one window column without the other, one window cell empty and the other not; a negative
        value, repeated names, a window not ``0 <= tw_start_s <= tw_end_s``.
    """
    names, xy = read_sites_csv(path, where)
    extra: dict[str, Any] = {}
    file = Path(path).name
    with open(Path(path), newline="", encoding="utf-8-sig") as fh:
        reader = csv.DictReader(fh)
        reader.fieldnames = [h.strip() for h in (reader.fieldnames or [])]
        present = [c for c in SITE_VALUE_COLUMNS if c in reader.fieldnames]
        tw = [c for c in SITE_WINDOW_COLUMNS if c in reader.fieldnames]
        if len(tw) == 1:
            missing = next(c for c in SITE_WINDOW_COLUMNS if c not in tw)
            raise DataError(f"sites file {file!r} has the column {tw[0]!r} but not {missing!r}; a time window "
                            "needs both (or neither)")
        for i, row in enumerate(reader):
            for col in present:
                text = (row.get(col) or "").strip()
                extra.setdefault(col, []).append(_number(text, 1.0 if col == "value" else 0.0, file, i, col))
            if tw:
                cells = [(row.get(c) or "").strip() for c in SITE_WINDOW_COLUMNS]
                if bool(cells[0]) != bool(cells[1]):
                    raise DataError(f"sites file {file!r}, line {i + 2}: tw_start_s is {cells[0]!r} and tw_end_s "
                                    f"is {cells[1]!r}; give both (a window) or leave both empty (none)")
                window = (tuple(_number(t, 0.0, file, i, c) for t, c in zip(cells, SITE_WINDOW_COLUMNS))
                          if cells[0] else None)
                extra.setdefault("time_window_s", []).append(window)
    return TourSites(names, xy, **extra)


def _number(text: str, default: float, file: str, i: int, col: str) -> float:
    """A cell of the sites file as a finite number (``default`` when empty)."""
    try:
        v = float(text) if text else default
    except ValueError:
        v = math.nan
    if not math.isfinite(v):
        raise DataError(f"sites file {file!r}, line {i + 2}: column {col!r} is {text!r}; expected a finite number")
    return v
