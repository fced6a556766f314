"""The (start, goal) pairs of a batch: checked arrays, read from a pairs CSV or made from every ordered pair of sites."""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrain.georef import lonlat_to_xy
from terrawatt_base.checks import readonly, real_array
from terrawatt_base.errors import DataError, FileFormatError, InvalidParameterError

__all__ = [
    "BatchPairs",
    "read_pairs_csv",
    "read_sites_csv",
    "PAIR_COLUMNS",
    "PAIR_LONLAT_COLUMNS",
    "SITE_COLUMNS",
    "SITE_LONLAT_COLUMNS",
]

#: Columns a pairs CSV must have (an optional ``name`` column labels each pair).
PAIR_COLUMNS = ("start_x_m", "start_y_m", "goal_x_m", "goal_y_m")
#: The columns of a pairs CSV in WGS 84 degrees, instead of :data:`PAIR_COLUMNS`.
PAIR_LONLAT_COLUMNS = ("start_lon", "start_lat", "goal_lon", "goal_lat")
#: Columns a sites CSV must have (an optional ``name`` column labels each site).
SITE_COLUMNS = ("x_m", "y_m")
#: The columns of a sites CSV in WGS 84 degrees, instead of :data:`SITE_COLUMNS`.
SITE_LONLAT_COLUMNS = ("lon", "lat")


@dataclass(frozen=True, eq=False)
class BatchPairs:
    """The (start, goal) pairs of a batch, with a name each.

    Attributes
    ----------
    names : tuple of str
        A unique label per pair (``"0"``, ``"1"``, ... when none were given).
    starts_xy_m, goals_xy_m : ndarray, shape (N, 2)
        Start and goal of each pair (m, read-only, finite).

    Raises
    ------
    InvalidParameterError
        No pairs, arrays of another shape, NaN / inf coordinates, names not matching the pairs.
    """

    names: tuple[str, ...]
    starts_xy_m: np.ndarray
    goals_xy_m: np.ndarray

    def __post_init__(self) -> None:
        starts = _points("starts_xy_m", self.starts_xy_m)
        goals = _points("goals_xy_m", self.goals_xy_m)
        if starts.shape != goals.shape:
            raise InvalidParameterError(f"starts_xy_m has {starts.shape[0]} points but goals_xy_m {goals.shape[0]}")
        if starts.shape[0] == 0:
            raise InvalidParameterError("a batch needs at least one (start, goal) pair, got none")
        names = tuple(self.names)
        if len(names) != starts.shape[0] or not all(isinstance(n, str) and n for n in names):
            raise InvalidParameterError(f"names must be {starts.shape[0]} non-empty strings, one per pair, got {names!r:.120}")
        if len(set(names)) != len(names):
            dup = next(n for n in names if names.count(n) > 1)
            raise InvalidParameterError(f"pair names must be unique; {dup!r} appears {names.count(dup)} times")
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "starts_xy_m", readonly(starts))
        object.__setattr__(self, "goals_xy_m", readonly(goals))

    def __len__(self) -> int:
        return len(self.names)

    @classmethod
    def from_array(cls, pairs: Any, names: Sequence[str] | None = None) -> BatchPairs:
        """Pairs from an ``(N, 4)`` array ``[start_x, start_y, goal_x, goal_y]`` or an ``(N, 2, 2)``
        array / sequence of ``((start_x, start_y), (goal_x, goal_y))``; a ``BatchPairs`` is returned as is.

        Examples
        --------
        >>> p = BatchPairs.from_array([((1.0, 1.0), (5.0, 5.0)), ((5.0, 5.0), (1.0, 1.0))])
        >>> len(p), p.names
        (2, ('0', '1'))
        """
        if isinstance(pairs, BatchPairs):
            if names is not None:
                raise InvalidParameterError("names must be None when pairs is already a BatchPairs (it has its names)")
            return pairs
        arr = real_array("pairs", pairs, finite=False)
        if arr.ndim == 3 and arr.shape[1:] == (2, 2):
            arr = arr.reshape(-1, 4)
        if arr.ndim != 2 or arr.shape[1] != 4:
            raise InvalidParameterError(
                f"pairs must have shape (N, 4) [start_x_m, start_y_m, goal_x_m, goal_y_m] or (N, 2, 2), got {arr.shape!r}"
            )
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad.size:
            raise InvalidParameterError(
                f"pairs row {int(bad[0])} has NaN/inf coordinates {arr[bad[0]].tolist()!r} ({bad.size} such rows); "
                "expected finite metres"
            )
        labels = tuple(str(i) for i in range(arr.shape[0])) if names is None else tuple(names)
        return cls(labels, arr[:, :2], arr[:, 2:])

    @classmethod
    def all_pairs(cls, sites_xy_m: Any, names: Sequence[str] | None = None) -> BatchPairs:
        """Every ordered pair of distinct sites (``N (N - 1)`` pairs: energy depends on direction).

        Pairs are named ``"A->B"`` from the site names (``"0"``, ``"1"``, ... when none).

        Examples
        --------
        >>> BatchPairs.all_pairs([(0.0, 0.0), (3.0, 0.0), (0.0, 4.0)], ["a", "b", "c"]).names
        ('a->b', 'a->c', 'b->a', 'b->c', 'c->a', 'c->b')
        """
        xy = _points("sites_xy_m", sites_xy_m)
        labels = tuple(str(i) for i in range(xy.shape[0])) if names is None else tuple(names)
        if len(labels) != xy.shape[0]:
            raise InvalidParameterError(f"names must give one name per site ({xy.shape[0]}), got {len(labels)}")
        if len(set(labels)) != len(labels):
            dup = next(n for n in labels if labels.count(n) > 1)
            raise InvalidParameterError(f"site names must be unique; {dup!r} appears {labels.count(dup)} times")
        if xy.shape[0] < 2:
            raise InvalidParameterError(f"all pairs of sites needs at least 2 sites, got {xy.shape[0]}")
        i, j = np.nonzero(~np.eye(xy.shape[0], dtype=bool))
        return cls(tuple(f"{labels[a]}->{labels[b]}" for a, b in zip(i, j)), xy[i], xy[j])


def _points(name: str, value: Any) -> np.ndarray:
    arr = real_array(name, value, finite=True)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidParameterError(f"{name} must have shape (N, 2) (x_m, y_m), got shape {arr.shape!r}")
    return arr


#: Largest points table (pairs, sites) read (bytes).
MAX_TABLE_BYTES = 64 * 1024**2
_RANGE_DEG = {"lon": 180.0, "lat": 90.0}


def _read_table(
    path: str | os.PathLike[str], column_sets: Sequence[tuple[Sequence[str], str]], what: str
) -> tuple[list[str] | None, np.ndarray, int]:
    """The optional ``name`` column and the numeric columns of one of ``column_sets`` (columns, unit) of a CSV file.

    The first set is the default: the file must hold it whole unless it holds another set
    whole (never two). Returns the names, the values and the index of the set found.
    """
    p = Path(path)
    if p.exists() and not p.is_file():  # a FIFO or a device would block or never end (a missing file: OSError)
        raise FileFormatError(f"{what} file {str(p)!r} is not a regular file")
    if p.is_file() and p.stat().st_size > MAX_TABLE_BYTES:
        raise FileFormatError(f"{what} file {str(p)!r} holds {p.stat().st_size} bytes; a table of points is at most "
                              f"{MAX_TABLE_BYTES // 1024**2} MiB")
    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            found = [k for k, (cols, _) in enumerate(column_sets) if all(c in header for c in cols)]
            if len(found) > 1:
                raise FileFormatError(
                    f"{what} file {p.name!r} has both the columns {list(column_sets[found[0]][0])!r} and "
                    f"{list(column_sets[found[1]][0])!r}; give the points one way"
                )
            if not found:
                required = column_sets[0][0]
                missing = [c for c in required if c not in header]
                others = "".join(f", or {list(cols)!r} ({unit})" for cols, unit in column_sets[1:])
                raise FileFormatError(
                    f"{what} file {p.name!r} lacks the column(s) {missing!r}; it has {header!r}; expected a header "
                    f"with {list(required)!r}{others} (and optionally 'name')"
                )
            kind = found[0]
            reader.fieldnames = header
            rows = list(reader)
    except (UnicodeDecodeError, csv.Error) as exc:
        raise FileFormatError(f"{what} file {p.name!r} is not a UTF-8 CSV table: {exc}") from exc
    if not rows:
        raise DataError(f"{what} file {p.name!r} has a header but no rows")
    required, unit = column_sets[kind]
    values = np.empty((len(rows), len(required)))
    for i, row in enumerate(rows):
        for k, col in enumerate(required):
            text = (row.get(col) or "").strip()
            try:
                v = float(text)
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise DataError(f"{what} file {p.name!r}, line {i + 2}: column {col!r} is {text!r}; expected a "
                                f"finite number of {unit}")
            limit = _RANGE_DEG.get(col.rsplit("_", 1)[-1]) if unit == "degrees" else None
            if limit is not None and abs(v) > limit:
                raise DataError(f"{what} file {p.name!r}, line {i + 2}: column {col!r} is {text!r}; expected degrees "
                                f"in [-{limit:g}, {limit:g}]")
            values[i, k] = v
    names = None
    if "name" in header:
        names = [(row.get("name") or "").strip() for row in rows]
        blank = [i + 2 for i, n in enumerate(names) if not n]
        if blank:
            raise DataError(f"{what} file {p.name!r}, line {blank[0]}: the name is empty; give every row a name")
        seen: set[str] = set()
        for i, n in enumerate(names):
            if n in seen:
                raise DataError(f"{what} file {p.name!r}, line {i + 2}: the name {n!r} is used twice; names must be unique")
            seen.add(n)
    return names, values, kind


def _metres(lonlat: np.ndarray, where: TerrainMap | None, path: str | os.PathLike[str], what: str) -> np.ndarray:
    """``(N, 2k)`` columns of (lon, lat) pairs as the map's metres.

    No bounds check: a point off the map is its row's error, as in metres."""
    if where is None:
        raise InvalidParameterError(
            f"{what} file {Path(path).name!r} gives longitude / latitude; pass where=<the georeferenced map> to place "
            "them on it"
        )
    out = np.empty_like(lonlat)
    for k in range(0, lonlat.shape[1], 2):
        x, y = lonlat_to_xy(lonlat[:, k], lonlat[:, k + 1], where.crs)
        out[:, k], out[:, k + 1] = x, y
    return out


def read_pairs_csv(path: str | os.PathLike[str], where: TerrainMap | None = None) -> BatchPairs:
    """Pairs from a CSV file with columns ``start_x_m, start_y_m, goal_x_m, goal_y_m`` (and optionally ``name``).

    The pairs may instead be given in WGS 84 degrees, columns ``start_lon, start_lat,
    goal_lon, goal_lat``: ``where`` (the georeferenced map) then places them in its metres
    (:meth:`terrain.TerrainMap.lonlat_to_xy`); a pair off the map is planned as an error
    row, like one in metres.

    Raises
    ------
    FileNotFoundError
        No such file.
    FileFormatError
        A required column is missing (the message lists the file's columns); both the
        metre and the degree columns.
    DataError
        No rows; an empty, non-numeric or NaN coordinate, degrees out of range (the message
        gives the line and column); an empty or repeated name.
    InvalidParameterError
        Degrees without ``where``, or a ``where`` without CRS.
    """
    names, values, kind = _read_table(path, ((PAIR_COLUMNS, "metres"), (PAIR_LONLAT_COLUMNS, "degrees")), "pairs")
    return BatchPairs.from_array(values if kind == 0 else _metres(values, where, path, "pairs"), names)


def read_sites_csv(
    path: str | os.PathLike[str], where: TerrainMap | None = None
) -> tuple[tuple[str, ...], np.ndarray]:
    """Sites from a CSV file with columns ``x_m, y_m`` (or ``lon, lat`` in WGS 84 degrees, placed on the
    georeferenced map ``where``), and optionally ``name``: names and an ``(N, 2)`` array of metres.

    Combine them with :meth:`BatchPairs.all_pairs`.

    Raises
    ------
    FileNotFoundError, FileFormatError, DataError, InvalidParameterError
        As :func:`read_pairs_csv`.
    """
    names, values, kind = _read_table(path, ((SITE_COLUMNS, "metres"), (SITE_LONLAT_COLUMNS, "degrees")), "sites")
    values = values if kind == 0 else _metres(values, where, path, "sites")
    labels = tuple(names) if names is not None else tuple(str(i) for i in range(values.shape[0]))
    return labels, readonly(values)
