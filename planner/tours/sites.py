"""A tour's sites (name, place, value, service, time window), its charging points and robots (battery, depot)."""

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
from terrawatt_base.errors import BlockedPositionError, DataError, InvalidParameterError, OutOfBoundsError

from ..batch_pairs import read_sites_csv
from ..edge_cost import EnergyCost

__all__ = ["TourSites", "TourRobot", "TourChargers", "read_tour_sites_csv", "read_tour_chargers_csv",
           "SITE_VALUE_COLUMNS", "SITE_WINDOW_COLUMNS", "CHARGER_COLUMNS"]

#: Optional columns of a tour's sites CSV beside the batch command's (default 1, 0 and 0).
SITE_VALUE_COLUMNS = ("value", "service_energy_j", "service_time_s")
#: Optional columns of a site's time window (s from the robots' departure; both or neither; empty: no window).
SITE_WINDOW_COLUMNS = ("tw_start_s", "tw_end_s")
#: Optional columns of a chargers CSV beside the sites' ``name, x_m, y_m`` (or ``name, lon, lat``): the charging
#: power (W; empty: to full at once, a battery swap), the fixed time of a stop (s, default 0) and how many stops the
#: fleet may make there in all (default 2).
CHARGER_COLUMNS = ("power_w", "connection_time_s", "max_visits")


def _named_points(what: str, names: Any, xy_m: Any) -> tuple[tuple[str, ...], np.ndarray]:
    """Unique non-empty names and their points ``(N, 2)``, N >= 1, checked together; ``what`` names one point."""
    xy = real_array("xy_m", xy_m, finite=True)
    if xy.ndim != 2 or xy.shape[1] != 2 or xy.shape[0] == 0:
        raise InvalidParameterError(f"{what}s' xy_m must have shape (N, 2) with N >= 1 {what}s, got shape {xy.shape!r}")
    n = xy.shape[0]
    names = tuple(names)
    if len(names) != n or not all(isinstance(s, str) and s for s in names):
        raise InvalidParameterError(f"{what}s' names must be {n} non-empty strings, one per {what}, got {names!r:.120}")
    if len(set(names)) != n:
        dup = next(s for s in names if names.count(s) > 1)
        raise InvalidParameterError(f"{what} names must be unique; {dup!r} appears {names.count(dup)} times")
    return names, xy


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
        names, xy = _named_points("site", self.names, self.xy_m)
        n = xy.shape[0]
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
        return _not_on(self.names, self.xy_m, cost)


def _not_on(names: tuple[str, ...], xy_m: np.ndarray, cost: EnergyCost) -> dict[str, str]:
    """The points of ``xy_m`` off ``cost``'s map or on a blocked cell, each with why (``"off the map: ..."``,
    ``"on an obstacle: ..."``)."""
    x, y = xy_m[:, 0], xy_m[:, 1]
    inside = np.asarray(cost.terrain.contains(x, y), dtype=bool)
    errors: dict[str, str] = {}
    for k in np.flatnonzero(~inside).tolist():
        errors[names[k]] = (f"off the map: ({x[k]:.6g}, {y[k]:.6g}) m lies outside the map bounds "
                            f"{tuple(round(b, 6) for b in cost.terrain.bounds)!r}")
    idx = np.flatnonzero(inside)
    if idx.size:
        r, c = cost.terrain.rowcol(x[idx], y[idx])
        for k in idx[np.asarray(cost.blocked)[r, c]].tolist():
            errors[names[k]] = (f"on an obstacle: ({x[k]:.6g}, {y[k]:.6g}) m lies on a blocked cell "
                                "(an obstacle or a slope above the limit)")
    return errors


@dataclass(frozen=True, eq=False)
class TourChargers:
    """Charging points a tour may stop at between its sites: each stop charges the battery **to full**.

    A stop takes ``connection_time_s`` plus the time to put back, at ``power_w``, the most a robot can
    have spent since its last charge (its battery from the reserve to full: the largest of the fleet),
    whatever it actually spent: the time is booked before the energy is known, so a tour on time in
    the plan is on time whatever the draw. The stop's time counts toward the sites' time windows and
    the robots' ``max_duration_s``. Charging costs no energy of the budget; after it, the next segment
    of the tour may spend ``(1 - reserve_soc) * capacity``.

    Attributes
    ----------
    names : tuple of str
        A unique, non-empty name per charger (what the result calls its stops).
    xy_m : ndarray, shape (C, 2)
        Places (m; :meth:`from_lonlat` for degrees).
    power_w : ndarray, shape (C,)
        Charging power (W, > 0; ``inf``, the default: to full at once, e.g. a battery swap).
    connection_time_s : ndarray, shape (C,)
        The fixed time of a stop (s, >= 0; default 0): docking, connecting, leaving.
    max_visits : ndarray of int, shape (C,)
        How many stops the fleet may make there in all (>= 1; default 2).

    Raises
    ------
    InvalidParameterError
        No chargers; repeated or empty names; NaN places; a power not > 0; a negative connection time;
        fewer than one visit (the charger named).

    Examples
    --------
    >>> ch = TourChargers(("dock",), [[20.0, 5.0]], power_w=100.0, connection_time_s=30.0)
    >>> ch.stop_time_s(36_000.0).tolist()  # 30 s to connect, 360 s to put back 10 Wh
    [390.0]
    """

    names: tuple[str, ...]
    xy_m: Any
    power_w: Any = None
    connection_time_s: Any = None
    max_visits: Any = None

    def __post_init__(self) -> None:
        names, xy = _named_points("charger", self.names, self.xy_m)
        n = xy.shape[0]
        power = (np.full(n, math.inf) if self.power_w is None
                 else real_array("power_w", self.power_w, finite=False).ravel() if np.ndim(self.power_w)
                 else np.full(n, float(self.power_w)))
        if power.shape != (n,):
            raise InvalidParameterError(f"power_w must hold one power per charger ({n}), got shape {power.shape!r}")
        for k in range(n):
            if not power[k] > 0:
                raise InvalidParameterError(f"power_w of charger {names[k]!r} must be > 0 (W; inf: to full at once), "
                                            f"got {float(power[k])!r}")
        visits = np.full(n, 2) if self.max_visits is None else np.asarray(self.max_visits).ravel() * np.ones(n)
        if visits.shape != (n,) or np.any(visits != np.round(visits)) or np.any(visits < 1):
            raise InvalidParameterError(f"max_visits must be one integer >= 1 per charger ({n}), got "
                                        f"{np.asarray(self.max_visits).tolist()!r}")
        set_ = object.__setattr__
        set_(self, "names", names)
        set_(self, "xy_m", readonly(xy))
        set_(self, "power_w", readonly(power))
        set_(self, "connection_time_s", _per_site("connection_time_s", self.connection_time_s, n, 0.0))
        set_(self, "max_visits", readonly(visits.astype(np.int64)))

    def __len__(self) -> int:
        return len(self.names)

    @classmethod
    def from_lonlat(cls, names: Any, lonlat: Any, where: TerrainMap, **per_charger: Any) -> TourChargers:
        """Chargers given as WGS 84 longitude, latitude (degrees), placed on the georeferenced map ``where``."""
        placed = TourSites.from_lonlat(names, lonlat, where)
        return cls(placed.names, placed.xy_m, **per_charger)

    def stop_time_s(self, refill_j: float) -> np.ndarray:
        """The time booked for a stop at each charger (s): its connection time plus ``refill_j`` at its power."""
        return self.connection_time_s + float(refill_j) / self.power_w

    def check_on(self, cost: EnergyCost) -> None:
        """Every charger must lie on a free cell of ``cost``'s map.

        Raises
        ------
        OutOfBoundsError
            A charger off the map (named).
        BlockedPositionError
            A charger on an obstacle or a slope above the limit (named).
        """
        for name, why in _not_on(self.names, self.xy_m, cost).items():
            error = OutOfBoundsError if why.startswith("off the map") else BlockedPositionError
            raise error(f"charger {name!r} is {why}")

    def to_dict(self) -> dict[str, Any]:
        """The chargers in tour.json: per name its place, power (null: to full at once), connection time, visits."""
        return {n: {"xy_m": [float(x), float(y)], "power_w": float(p) if math.isfinite(p) else None,
                    "connection_time_s": float(c), "max_visits": int(v)}
                for n, (x, y), p, c, v in zip(self.names, self.xy_m.tolist(), self.power_w.tolist(),
                                              self.connection_time_s.tolist(), self.max_visits.tolist())}


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
    standby_power_w : float
        What the robot draws while it waits for a site's window to open (W, >= 0; default 0): its electronics
        at standstill (sensors and the control board's standby; the edge costs carry them while driving).
        :func:`planner.tours.plan_tour_on_map` takes the robot's ``sensor_power_w + control_standby_power_w``.

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
    standby_power_w: float = 0.0

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
        object.__setattr__(self, "standby_power_w", check_real("standby_power_w", self.standby_power_w, low=0.0))

    @property
    def budget_j(self) -> float:
        """Energy the tour may spend above the reserve (J): ``(initial_soc - reserve_soc) * capacity``."""
        b = self.battery
        return max(b.initial_soc - b.reserve_soc, 0.0) * b.energy_capacity_j

    @property
    def full_budget_j(self) -> float:
        """Energy a tour may spend above the reserve after a charge to full (J): ``(1 - reserve_soc) * capacity``."""
        b = self.battery
        return max(1.0 - b.reserve_soc, 0.0) * b.energy_capacity_j

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


def read_tour_chargers_csv(path: str | os.PathLike[str], where: TerrainMap | None = None) -> TourChargers:
    """Charging points from a CSV laid out as the sites file (``name, x_m, y_m`` or ``name, lon, lat``) with the
    optional columns :data:`CHARGER_COLUMNS`: ``power_w`` (W; empty: to full at once), ``connection_time_s``
    (s, default 0) and ``max_visits`` (default 2).

    Raises
    ------
    FileNotFoundError, FileFormatError, DataError, InvalidParameterError
        As :func:`read_tour_sites_csv`; a cell that is not a number (the line and column named); a power not > 0,
        a negative connection time, a number of visits that is not an integer >= 1, repeated names.
    """
    names, xy = read_sites_csv(path, where)
    file = Path(path).name
    extra: dict[str, list[float]] = {}
    with open(Path(path), newline="", encoding="utf-8-sig") as fh:
        reader = csv.DictReader(fh)
        reader.fieldnames = [h.strip() for h in (reader.fieldnames or [])]
        present = [c for c in CHARGER_COLUMNS if c in reader.fieldnames]
        defaults = {"power_w": math.inf, "connection_time_s": 0.0, "max_visits": 2.0}
        for i, row in enumerate(reader):
            for col in present:
                text = (row.get(col) or "").strip()
                if col == "power_w" and not text:
                    extra.setdefault(col, []).append(math.inf)
                    continue
                extra.setdefault(col, []).append(_number(text, defaults[col], file, i, col))
    return TourChargers(names, xy, **extra)
