"""BatchResult: one row per (start, goal) pair of a batch (energy, length, time, status, saving, error): the printed
summary, batch.csv and batch.json, the figure of the routes' energies."""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base import plot_target
from terrawatt_base.answer import fmt_fixed, write_answer
from terrawatt_base.atomic import save_figure, write_text_atomic
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import result_document, write_result_json
from terrawatt_base.plot_target import check_ax, check_plot_target

from .route import ROUTE_STATUSES

__all__ = ["BatchRow", "BatchResult", "BATCH_STATUSES", "BATCH_FORMAT_VERSION"]

#: Status of a row: a route status, or ``"error"`` when planning the pair raised.
BATCH_STATUSES = (*ROUTE_STATUSES, "error")
#: Version of the JSON layout of :meth:`BatchResult.to_dict` (batch.json).
BATCH_FORMAT_VERSION = 1


@dataclass(frozen=True)
class BatchRow:
    """The outcome of one pair.

    Attributes
    ----------
    name : str
        The pair's name.
    start_x_m, start_y_m, goal_x_m, goal_y_m : float
        The query (m).
    status : str
        One of :data:`BATCH_STATUSES`.
    energy_j, energy_wh, length_m, duration_s : float
        The route's energy (segments and turns), length and driving time; NaN when no route.
    shortest_energy_j : float
        Energy of the shortest-distance route between the same points (NaN when none).
    energy_saved_pct : float
        Saving of the minimum-energy route against the shortest one (%); NaN unless both exist.
    planning_time_s : float
        Planning time of the route (s, on the worker that planned it).
    error : str
        ``"ExceptionType: message"`` for status ``"error"``, else empty.
    """

    name: str
    start_x_m: float
    start_y_m: float
    goal_x_m: float
    goal_y_m: float
    status: str
    energy_j: float = math.nan
    energy_wh: float = math.nan
    length_m: float = math.nan
    duration_s: float = math.nan
    shortest_energy_j: float = math.nan
    energy_saved_pct: float = math.nan
    planning_time_s: float = math.nan
    error: str = ""

    def __post_init__(self) -> None:
        if self.status not in BATCH_STATUSES:
            raise InvalidParameterError(f"status must be one of {list(BATCH_STATUSES)!r}, got {self.status!r}")
        if (self.status == "error") != bool(self.error):
            raise InvalidParameterError(f"a row has error text exactly when its status is 'error'; got {self.status!r}")

    @property
    def found(self) -> bool:
        """The pair has a route (``exact`` or ``approximate``)."""
        return self.status in ("exact", "approximate")


#: Errors listed by :meth:`BatchResult.summary` (the rows hold them all).
_SHOWN_ERRORS = 10
#: CSV / JSON columns of a row, in order.
_COLUMNS = tuple(f.name for f in fields(BatchRow))


@dataclass(frozen=True)
class BatchResult:
    """The rows of a batch, in the order of its pairs, how it ran and on which map.

    Made by :func:`planner.plan_batch` (and :func:`planner.batch.plan_batch_on_map`, which prices
    the map first). :meth:`summary` is the text ``terrawatt batch`` prints, :meth:`write` writes
    batch.csv and batch.json.

    Attributes
    ----------
    rows : tuple of BatchRow
    planner : str
        Planner name (see :data:`planner.PLANNERS`).
    where : str
        ``"in process"``, ``"local cluster"`` or the scheduler address.
    n_workers : int
        Dask workers that planned (1 in process).
    elapsed_s : float
        Wall time of the planning (shipping the cost to the workers included, starting a
        local cluster not).
    map_label : str
        How the map is named.
    terrain : TerrainMap, optional
        The map the pairs were planned on (not part of the JSON).

    Examples
    --------
    >>> r = BatchResult((BatchRow("a", 0.0, 0.0, 1.0, 1.0, "exact", energy_j=7.2e3),), "lattice", "in process", 1, 0.5)
    >>> r.n_found, r.routes_per_s
    (1, 2.0)
    """

    rows: tuple[BatchRow, ...]
    planner: str
    where: str
    n_workers: int
    elapsed_s: float
    map_label: str = "map"
    terrain: TerrainMap | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        rows = tuple(self.rows)
        if not all(isinstance(r, BatchRow) for r in rows):
            raise InvalidParameterError("rows must be BatchRow objects")
        object.__setattr__(self, "rows", rows)

    def __len__(self) -> int:
        return len(self.rows)

    def count(self, status: str) -> int:
        """Rows of a status."""
        return sum(r.status == status for r in self.rows)

    @property
    def n_found(self) -> int:
        """Pairs with a route."""
        return sum(r.found for r in self.rows)

    @property
    def all_found(self) -> bool:
        """Whether every pair has a route."""
        return self.n_found == len(self.rows)

    @property
    def n_errors(self) -> int:
        """Pairs whose planning raised."""
        return self.count("error")

    @property
    def routes_per_s(self) -> float:
        """Pairs planned per second of wall time (all rows, errors included)."""
        return len(self.rows) / self.elapsed_s if self.elapsed_s > 0 else math.nan

    def column(self, name: str) -> np.ndarray:
        """One column over the rows as an array (numbers as float64, text as str).

        Raises
        ------
        InvalidParameterError
            Not a column name.
        """
        if name not in _COLUMNS:
            raise InvalidParameterError(f"column must be one of {list(_COLUMNS)!r}, got {name!r}")
        return np.array([getattr(r, name) for r in self.rows])

    def median_saving_pct(self) -> float:
        """Median energy saving vs the shortest route over the pairs that have both (NaN if none)."""
        s = self.column("energy_saved_pct").astype(float)
        s = s[np.isfinite(s)]
        return float(np.median(s)) if s.size else math.nan

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-friendly result document, format ``terrawatt-batch`` (NaN stays NaN here; :meth:`write`
        writes it as null)."""
        return result_document("batch", BATCH_FORMAT_VERSION, {
            "planner": self.planner,
            "where": self.where,
            "n_workers": self.n_workers,
            "elapsed_s": self.elapsed_s,
            "routes_per_s": self.routes_per_s,
            "n_pairs": len(self.rows),
            "counts": {s: self.count(s) for s in BATCH_STATUSES},
            "median_energy_saved_pct": self.median_saving_pct(),
            "rows": [asdict(r) for r in self.rows],
        })

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write one line per row (header: the :class:`BatchRow` fields; NaN as an empty cell), atomically."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(_COLUMNS)
        for r in self.rows:
            writer.writerow(["" if isinstance(v, float) and not math.isfinite(v) else v for v in
                             (getattr(r, c) for c in _COLUMNS)])
        return write_text_atomic(path, buf.getvalue())

    def table(self, max_rows: int = 20) -> str:
        """The first ``max_rows`` rows as a fixed-width text table (name, status, Wh, m, s, saving)."""
        header = f"{'pair':<20} {'status':<11} {'energy Wh':>9} {'length m':>9} {'time s':>8} {'saved %':>8}"
        lines = [header, "-" * len(header)]
        for r in self.rows[:max_rows]:
            wh, m, s, pct = (fmt_fixed(x, d, missing="-") for x, d in
                             ((r.energy_wh, 2), (r.length_m, 1), (r.duration_s, 1), (r.energy_saved_pct, 1)))
            lines.append(f"{r.name[:20]:<20} {r.status:<11} {wh:>9} {m:>9} {s:>8} {pct:>8}")
        if len(self.rows) > max_rows:
            lines.append(f"... {len(self.rows) - max_rows} more rows")
        return "\n".join(lines)

    def header(self) -> str:
        """``map: LABEL  R x C cells of S m; N pairs; planner NAME``: the first line of the summary."""
        t = self.terrain
        grid = "" if t is None else f"  {t.shape[0]} x {t.shape[1]} cells of {t.cell_size_m:g} m"
        return f"map: {self.map_label}{grid}; {len(self.rows)} pairs; planner {self.planner}"

    def summary(self) -> str:
        """What ``terrawatt batch`` prints: :meth:`header`, the table of the pairs (:meth:`table`), :meth:`totals`."""
        return "\n".join([self.header(), self.table(), "", self.totals()])

    def write(self, out_dir: str | os.PathLike[str]) -> list[Path]:
        """Write batch.csv and batch.json into ``out_dir`` (created); return them."""
        return write_answer(out_dir, {"batch.csv": self.to_csv,
                                      "batch.json": lambda p: write_result_json(p, self.to_dict())})

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None, title: str | None = None,
             dpi: int = 110) -> Path | Any:
        """The routes' energies: a bar per pair (Wh of the minimum-energy route) with the shortest-distance
        route's energy as a tick beside it; a pair without a route (no route, an error) is marked at zero.

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax`` (a matplotlib
        Axes to draw into; nothing is written and it is returned).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or ``ax``; a batch without pairs.
        """
        target = check_plot_target(path, ax)
        if not self.rows:
            raise InvalidParameterError("the batch has no pairs: there is no energy to draw")
        if target is None:
            _draw_energies(check_ax(ax), self, title)
            return ax
        fig, axes = plot_target.new_figure((max(6.0, min(16.0, 0.45 * len(self.rows) + 2.0)), 4.2))
        _draw_energies(axes, self, title)
        fig.tight_layout()
        return save_figure(fig, target, dpi=dpi, format="png")

    def totals(self) -> str:
        """A few lines for people: counts by status, throughput, median saving, the errors."""
        counts = ", ".join(f"{self.count(s)} {s}" for s in BATCH_STATUSES if self.count(s))
        lines = [
            f"{len(self.rows)} pairs ({counts}) planned with {self.planner} in {self.elapsed_s:.2f} s "
            f"on {self.n_workers} worker(s) ({self.where}): {self.routes_per_s:.1f} routes/s",
        ]
        saving = self.median_saving_pct()
        if math.isfinite(saving):
            lines.append(f"median energy saved vs the shortest route: {saving:.1f} %")
        found = [r for r in self.rows if r.found]
        if found:
            e = np.array([r.energy_wh for r in found])
            lines.append(f"route energy: min {e.min():.2f} Wh, median {np.median(e):.2f} Wh, max {e.max():.2f} Wh")
        errors = [r for r in self.rows if r.status == "error"]
        lines += [f"error in pair {r.name!r}: {r.error}" for r in errors[:_SHOWN_ERRORS]]
        if len(errors) > _SHOWN_ERRORS:
            lines.append(f"... and {len(errors) - _SHOWN_ERRORS} more errors (see the rows' error column)")
        return "\n".join(lines)


def _draw_energies(ax: Any, result: BatchResult, title: str | None) -> None:
    """A bar per pair (the minimum-energy route, Wh), a tick at the shortest route's energy, a red x where none."""
    x = np.arange(len(result.rows))
    wh = result.column("energy_wh").astype(float)
    found = np.isfinite(wh)
    ax.bar(x[found], wh[found], color="tab:green", label="minimum-energy route")
    shortest = result.column("shortest_energy_j").astype(float) / 3600.0
    if np.isfinite(shortest).any():
        ax.plot(x, shortest, "_", color="black", markersize=14, markeredgewidth=2, label="shortest-distance route")
    if not found.all():
        ax.plot(x[~found], np.zeros(int(np.count_nonzero(~found))), "x", color="tab:red", clip_on=False,
                label="no route")
    if len(x) > 40:  # names would overlap: the pairs' order only
        ax.set_xticks([])
        ax.set_xlabel(f"{len(x)} pairs, in order")
    else:
        tilted = {"rotation": 60, "ha": "right", "fontsize": 8} if len(x) > 8 else {}
        ax.set_xticks(x, [r.name for r in result.rows], **tilted)
    ax.set_ylabel("route energy (Wh)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or f"{result.map_label}: {len(result.rows)} pairs, planner {result.planner}")
