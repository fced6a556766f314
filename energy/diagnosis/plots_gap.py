"""Figures of where a gap lies: residual over time per side, gap by regime, gap on the map.

Where a figure goes is the rule of :mod:`energy.diagnosis.plots` (give ``path`` or
``ax=``; see there); a figure for ``path`` is made by
:func:`terrawatt_base.plot_target.new_figure` (no pyplot) and written by
:func:`terrawatt_base.atomic.save_figure`. The helpers shared with it (argument checks, the
reasons a figure's data is missing) live here too.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrain.terrain_map import TerrainMap
from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.checks import check_int, check_real, fmt_number, fmt_pct
from terrawatt_base.errors import DataError, GridMismatchError, InvalidParameterError
from terrawatt_base.plot_target import check_ax, check_axes, check_plot_target

from ..logs import InteractionLog
from ..metrics import DEFAULT_SECTION_S, DEFAULT_SMOOTHING_SAMPLES, moving_median
from .gap import SIDES, checked_pairs, sample_gap_mah, time_labels
from .regimes import (
    ACCELERATION_LABELS,
    GRADE_LABELS,
    OFF_MAP_LABEL,
    SPEED_LABELS,
    TURNING_LABELS,
    UNKNOWN_LABEL,
    check_terrain,
)
from .stage import Stage

__all__ = [
    "REGIME_PANELS",
    "checked_diagnosis",
    "log_list",
    "regime_rows",
    "missing_regimes_reason",
    "missing_map_reason",
    "plot_residual_time",
    "plot_gap_by_regime",
    "plot_gap_map",
]

#: Localisation dimensions drawn by :func:`plot_gap_by_regime`, one panel each, in order.
REGIME_PANELS = ("speed", "turning", "acceleration", "grade", "ground", "side")

_ORDERS = {"speed": SPEED_LABELS, "turning": TURNING_LABELS, "acceleration": ACCELERATION_LABELS,
           "grade": GRADE_LABELS, "side": SIDES}
_SIDE_COLOURS = ("#08519c", "#d94801")
_GAP_COLOURS = ("#fb6a4a", "#6baed6")  # shade of a section whose gap is >= 0 (model predicts too little), < 0
_LABELLED_SECTIONS = 6  # sections of a run labelled with their gap: the largest |gap|
_BLOCK = re.compile(r"^cells? \((\d+)(?:-(\d+))?, (\d+)(?:-(\d+))?\)$")


def checked_diagnosis(diagnosis: Any) -> Any:
    """``diagnosis`` if it is a :class:`~energy.diagnosis.Diagnosis` (its current stage a :class:`Stage`), else
    InvalidParameterError. (The figures stand below the answer that draws them: they know it by its stage.)"""
    if not isinstance(getattr(diagnosis, "current", None), Stage) or not hasattr(diagnosis, "localisation"):
        raise InvalidParameterError(f"diagnosis must be a Diagnosis, got {type(diagnosis).__name__!r}")
    return diagnosis


def log_list(logs: Any) -> list[Any]:
    """A log or a sequence of logs as a list (InvalidParameterError for anything else)."""
    if isinstance(logs, InteractionLog):
        return [logs]
    if isinstance(logs, (str, bytes)) or not isinstance(logs, Sequence):
        raise InvalidParameterError(f"logs must be an InteractionLog or a sequence of them, got {type(logs).__name__!r}")
    return list(logs)


# ----------------------------------------------------------------- residual over time
def _runs_to_draw(gaps: Sequence[float], runs: Sequence[int] | None, max_runs: int) -> list[int]:
    n = len(gaps)
    if runs is None:
        order = sorted(range(n), key=lambda i: (-abs(gaps[i]), i))
        return sorted(order[:max_runs])
    if isinstance(runs, (str, bytes)) or not isinstance(runs, Sequence) or not runs:
        raise InvalidParameterError(f"runs must be None or a non-empty sequence of run indices, got {runs!r:.80}")
    chosen = [check_int(f"runs[{k}]", r, low=0, high=n - 1) for k, r in enumerate(runs)]
    if len(set(chosen)) != len(chosen):
        raise InvalidParameterError(f"runs has duplicates: {chosen!r}")
    if len(chosen) > max_runs:
        raise InvalidParameterError(f"runs names {len(chosen)} runs; at most max_runs = {max_runs} are drawn")
    return chosen


def plot_residual_time(logs: Any, predictions: Any, path: str | os.PathLike[str] | None = None, *,
                       ax: Sequence[Any] | None = None, corrected: Any = None, runs: Sequence[int] | None = None,
                       max_runs: int = 4, section_s: float = DEFAULT_SECTION_S,
                       window_samples: int = DEFAULT_SMOOTHING_SAMPLES, dpi: int = 110) -> Path | tuple[Any, ...]:
    """Residual current (measured - predicted) over time per side, one panel per run, sections shaded.

    Each panel shows the left and right residual (thin) and their moving medians (thick);
    the ``section_s`` time sections of :func:`~energy.diagnosis.gap.time_labels` are
    shaded in proportion to the gap they carry (red: the model predicts too little, blue:
    too much), the six largest labelled with it (mAh). With ``corrected`` the residual of the corrected model is drawn dashed.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
    predictions : array_like (N, 2) or sequence of them
        ``[left, right]`` predicted current (A) of the model as given, per log.
    path : path-like, optional
        PNG file to write (or give ``ax``).
    ax : sequence of matplotlib Axes, optional
        One per run drawn (``len(runs)``, or by default ``min(max_runs, number of logs)``):
        draw into these instead of writing a file.
    corrected : sequence of array_like (N, 2), optional
        Predictions of the corrected model, per log (label says "in-sample" when it was
        fitted on these logs, as :attr:`Diagnosis.corrected_model` is).
    runs : sequence of int, optional
        Runs to draw (indices into ``logs``); default the ``max_runs`` runs with the
        largest whole-run ``|gap|``. The title says which.
    max_runs : int
        At most this many panels (1 to 8).
    section_s : float
        Section length (s), > 0.
    window_samples : int
        Moving-median window (samples), >= 1.
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or tuple of Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; ``path`` is a folder or lies under a file
        (checked before drawing); not one axes per run drawn; bad logs, predictions, runs
        or numbers.
    DataError
        A log with fewer than 2 samples; non-finite predictions.
    """
    target = check_plot_target(path, ax)
    max_runs = check_int("max_runs", max_runs, low=1, high=8)
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    window_samples = check_int("window_samples", window_samples, low=1)
    dpi = check_int("dpi", dpi, low=10, high=1200)
    items, preds = checked_pairs(logs, predictions)
    after = checked_pairs(items, corrected)[1] if corrected is not None else None
    sample_gaps = [sample_gap_mah(log, p) for log, p in zip(items, preds)]
    chosen = _runs_to_draw([float(g.sum()) for g in sample_gaps], runs, max_runs)
    if target is None:
        what = f"one per run drawn: runs {', '.join(map(str, chosen))}; choose them with runs= or max_runs="
        panels = check_axes(ax, len(chosen), what=what)
        _draw_residual_runs(panels, items, preds, after, sample_gaps, chosen, section_s, window_samples)
        return panels

    fig, grid = plot_target.new_figure((10, 2.6 * len(chosen) + 0.8), len(chosen), 1, squeeze=False)
    _draw_residual_runs(grid[:, 0], items, preds, after, sample_gaps, chosen, section_s, window_samples)
    which = "chosen" if runs is not None else "largest |gap|"
    fig.suptitle(f"residual current (measured - predicted): runs {', '.join(map(str, chosen))} of {len(items)} ({which})")
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_residual_runs(panels: Sequence[Any], items: Sequence[InteractionLog], preds: Sequence[np.ndarray],
                        after: Sequence[np.ndarray] | None, sample_gaps: Sequence[np.ndarray], chosen: Sequence[int],
                        section_s: float, window_samples: int) -> None:
    """The panels of :func:`plot_residual_time`, run ``chosen[k]`` into ``panels[k]``."""
    for ax, i in zip(panels, chosen):
        log, pred = items[i], preds[i]
        t = log.time_s - log.time_s[0]
        res = np.column_stack([log.current_left_a, log.current_right_a]) - pred
        labels = time_labels(log, i, section_s)
        names, inv = np.unique(labels, return_inverse=True)
        inv = inv.reshape(-1)
        gaps = np.bincount(inv, weights=sample_gaps[i].sum(axis=1), minlength=names.size)
        first = np.full(names.size, len(log))
        np.minimum.at(first, inv, np.arange(len(log)))
        order = np.argsort(first)  # sections in time order
        starts = t[first[order]]
        ends = np.append(starts[1:], t[-1])
        peak = float(np.max(np.abs(gaps))) or 1.0
        labelled = set(np.argsort(-np.abs(gaps))[:_LABELLED_SECTIONS].tolist())
        for a, b, k in zip(starts, ends, order):
            ax.axvspan(a, b, color=_GAP_COLOURS[int(gaps[k] < 0)], alpha=0.06 + 0.34 * abs(gaps[k]) / peak, lw=0)
            if k in labelled:
                ax.text(0.5 * (a + b), 1.0, fmt_number(gaps[k], 2), transform=ax.get_xaxis_transform(), ha="center",
                        va="bottom", fontsize=7, color="#67000d" if gaps[k] >= 0 else "#08306b")
        smooth = moving_median(res, min(window_samples, len(log)))
        for s, side in enumerate(SIDES):
            ax.plot(t, res[:, s], color=_SIDE_COLOURS[s], lw=0.5, alpha=0.35)
            ax.plot(t, smooth[:, s], color=_SIDE_COLOURS[s], lw=1.6, label=f"{side}, moving median")
            if after is not None:
                ra = np.column_stack([log.current_left_a, log.current_right_a])[:, s] - after[i][:, s]
                ax.plot(t, moving_median(ra, min(window_samples, len(log))), color=_SIDE_COLOURS[s], lw=1.2, ls="--",
                        label=f"{side}, corrected (in-sample)")
        ax.axhline(0.0, color="k", lw=0.6)
        src = Path(log.meta.source).name or "run"
        ax.set_ylabel("residual (A)")
        ax.set_title(f"run {i}: {src}, {log.meta.ground_label or 'unknown ground'}, gap "
                     f"{fmt_number(float(sample_gaps[i].sum()), 3)} mAh", fontsize=9, loc="left", pad=12)
        ax.grid(alpha=0.3)
    panels[0].legend(loc="upper right", fontsize=7, ncol=2)
    panels[-1].set_xlabel(f"time from the run's start (s); shaded: {fmt_number(section_s)} s sections by their gap "
                          "(mAh; red: predicted too little, blue: too much)")


# ----------------------------------------------------------------- gap by regime
def regime_rows(diagnosis: Any) -> dict[str, list[Any]]:
    """The known, non-empty localisation rows of each :data:`REGIME_PANELS` dimension, in a natural order."""
    out: dict[str, list[Any]] = {}
    for dim in REGIME_PANELS:
        rows = [r for r in diagnosis.localisation if r.dimension == dim and r.label != UNKNOWN_LABEL and r.n_samples]
        if rows:
            order = _ORDERS.get(dim)
            if order is not None:
                rows.sort(key=lambda r: order.index(r.label) if r.label in order else len(order))
            out[dim] = rows
    return out


def plot_gap_by_regime(diagnosis: Any, path: str | os.PathLike[str] | None = None, *,
                       ax: Sequence[Any] | None = None, dpi: int = 110) -> Path | tuple[Any, ...]:
    """The net gap (mAh) by operating regime: one bar chart per dimension of :data:`REGIME_PANELS`.

    Bars are the net signed gap of each slice (measured - predicted charge, the model as
    given, all logs) from :attr:`Diagnosis.localisation`, with its 95 % bootstrap interval
    as an error bar, labelled with the gap as a percentage of the slice's own measured
    charge and the time behind it; a dimension the logs cannot tell (only ``"unknown"``)
    gets no panel and is named in the figure's note (drawn with ``path``).

    Parameters
    ----------
    diagnosis : Diagnosis
    path : path-like, optional
        PNG file to write (or give ``ax``).
    ax : sequence of matplotlib Axes, optional
        One per dimension with a known slice (the keys of :func:`regime_rows`, in the
        order of :data:`REGIME_PANELS`): draw into these instead of writing a file.
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or tuple of Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Not a Diagnosis; both or neither of ``path`` and ``ax``; a bad ``path``
        (checked before drawing); not one axes per dimension drawn.
    DataError
        No dimension has a known slice.
    """
    diagnosis = checked_diagnosis(diagnosis)
    target = check_plot_target(path, ax)
    dpi = check_int("dpi", dpi, low=10, high=1200)
    why = missing_regimes_reason(diagnosis)
    if why:
        raise DataError(why)
    rows = regime_rows(diagnosis)
    if target is None:
        panels = check_axes(ax, len(rows), what="one per dimension: " + ", ".join(map(repr, rows)))
        _draw_regimes(panels, rows)
        return panels

    ncols = 3 if len(rows) > 2 else len(rows)
    nrows = -(-len(rows) // ncols)
    fig, grid = plot_target.new_figure((4.2 * ncols, 3.2 * nrows + 0.6), nrows, ncols, squeeze=False)
    _draw_regimes(grid.ravel()[:len(rows)], rows)
    for spare in grid.ravel()[len(rows):]:
        spare.set_visible(False)
    missing = [d for d in REGIME_PANELS if d not in rows]
    note = f"; not known from these logs: {', '.join(missing)}" if missing else ""
    fig.suptitle(f"where the gap lies (model as given, all logs; bar = net measured - predicted charge, "
                 f"95 % interval over {diagnosis.localisation_units}){note}", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_regimes(panels: Sequence[Any], rows: dict[str, list[Any]]) -> None:
    """The panels of :func:`plot_gap_by_regime`, one dimension of ``rows`` per axes."""
    for ax, (dim, rs) in zip(panels, rows.items()):
        y = np.arange(len(rs))
        gaps = np.array([r.gap_mah for r in rs])
        lo = np.array([r.gap_interval_mah[0] for r in rs])
        hi = np.array([r.gap_interval_mah[1] for r in rs])
        err = np.nan_to_num(np.maximum(np.stack([gaps - lo, hi - gaps]), 0.0))
        bars = ax.barh(y, gaps, xerr=err, color=np.where(gaps >= 0, "#de2d26", "#3182bd"), alpha=0.8,
                       error_kw={"elinewidth": 0.8, "capsize": 2, "ecolor": "0.3"})
        ax.bar_label(bars, [f"{fmt_pct(r.gap_pct)} % of its charge, {fmt_number(r.duration_s, 3)} s" for r in rs],
                     padding=3, fontsize=7)
        ax.set_yticks(y, [r.label for r in rs], fontsize=8)
        ax.invert_yaxis()
        ax.axvline(0.0, color="k", lw=0.6)
        ax.margins(x=0.3)
        ax.set_title(dim, fontsize=10)
        ax.set_xlabel("net gap (mAh)", fontsize=8)
        ax.grid(axis="x", alpha=0.3)


def missing_regimes_reason(diagnosis: Any) -> str:
    """Why :func:`plot_gap_by_regime` has nothing to draw, or ``""``."""
    if regime_rows(diagnosis):
        return ""
    return "no regime figure: the diagnosis localises no gap by regime (every regime slice is unknown or empty)"


# ----------------------------------------------------------------- gap on the map
def _blocks(diagnosis: Any) -> list[tuple[int, int, int, int, float]]:
    out = []
    for r in diagnosis.localisation:
        if r.dimension != "space":
            continue
        m = _BLOCK.match(r.label)
        if m:
            r0, r1, c0, c1 = m.group(1), m.group(2) or m.group(1), m.group(3), m.group(4) or m.group(3)
            out.append((int(r0), int(r1), int(c0), int(c1), r.gap_mah))
    return out


def missing_map_reason(diagnosis: Any, terrain: Any, logs: Any) -> str:
    """Why :func:`plot_gap_map` has nothing to draw (no poses, no map, no block), or ``""``."""
    if logs is not None and all(getattr(log, "pose_xyh", None) is None for log in log_list(logs)):
        return "no map figure: the logs carry no poses, so the gap cannot be placed on a map"
    if terrain is None:
        return "no map figure: no terrain map given (the map the runs drove on)"
    if not _blocks(diagnosis):
        labels = {r.label for r in diagnosis.localisation if r.dimension == "space"}
        if labels == {OFF_MAP_LABEL}:
            return "no map figure: every pose of the logs lies off the map"
        return ("no map figure: the diagnosis has no map blocks (its logs carry no poses, or it was run "
                "without a terrain)")
    return ""


def plot_gap_map(diagnosis: Any, terrain: TerrainMap, path: str | os.PathLike[str] | None = None, *,
                 ax: Any = None, logs: Any = None, dpi: int = 110) -> Path | Any:
    """The gap on the map: the ``"space"`` rows of :attr:`Diagnosis.localisation` over a hillshade and contours.

    Each map block (about :data:`~energy.diagnosis.regimes.SPACE_BLOCK_M` wide) the runs
    crossed is coloured by its gap (mAh, red: the model predicts too little, blue: too
    much), over a hillshade of the elevation; ``logs`` with poses add their tracks. The
    colour bar is attached to the axes' figure, beside the axes.

    Parameters
    ----------
    diagnosis : Diagnosis
        Run with ``terrain`` on logs with poses.
    terrain : TerrainMap
        The map the diagnosis ran on.
    path : path-like, optional
        PNG file to write (or give ``ax``).
    ax : matplotlib Axes, optional
        Draw into these axes instead of writing a file.
    logs : InteractionLog or sequence of them, optional
        Tracks to draw.
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Not a Diagnosis or TerrainMap; both or neither of ``path`` and ``ax``; a bad
        ``path`` (checked before drawing) or ``ax``.
    DataError
        No map blocks (logs without poses, no terrain); the message says which.
    GridMismatchError
        A block lies outside ``terrain`` (not the map the diagnosis ran on).
    """
    diagnosis = checked_diagnosis(diagnosis)
    terrain = check_terrain(terrain)
    target = check_plot_target(path, ax)
    if target is None:
        ax = check_ax(ax)
    dpi = check_int("dpi", dpi, low=10, high=1200)
    why = missing_map_reason(diagnosis, terrain, logs)
    if why:
        raise DataError(why)
    blocks = _blocks(diagnosis)
    rows, cols = terrain.shape
    raster = np.full(terrain.shape, np.nan)
    for r0, r1, c0, c1, gap in blocks:
        if r1 >= rows or c1 >= cols:
            raise GridMismatchError(f"map block cells ({r0}-{r1}, {c0}-{c1}) lie outside the terrain's {rows} x {cols} "
                                    "cells; give the map the diagnosis ran on")
        raster[r0:r1 + 1, c0:c1 + 1] = gap
    if target is None:
        _draw_gap_map(ax, terrain, raster, blocks, logs)
        return ax

    fig, ax = plot_target.new_figure((7.5, 6.4))
    _draw_gap_map(ax, terrain, raster, blocks, logs)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_gap_map(ax: Any, terrain: TerrainMap, raster: np.ndarray, blocks: list[tuple[int, int, int, int, float]],
                  logs: Any) -> None:
    """The map of :func:`plot_gap_map`, drawn into ``ax`` (its colour bar beside ``ax`` in ``ax.figure``)."""
    from matplotlib.colors import LightSource

    xmin, ymin, xmax, ymax = terrain.bounds
    extent = (xmin, xmax, ymin, ymax)
    shade = LightSource(azdeg=315, altdeg=45).hillshade(terrain.elevation_m, vert_exag=3.0, dx=terrain.cell_size_m,
                                                         dy=terrain.cell_size_m)
    ax.imshow(shade, cmap="gray", extent=extent, origin="lower", vmin=0, vmax=1, interpolation="bilinear")
    z = terrain.elevation_m
    if float(z.max()) > float(z.min()):
        xs, ys = terrain.cell_centres()
        cs = ax.contour(xs, ys, z, levels=np.linspace(float(z.min()), float(z.max()), 12)[1:-1], colors="k",
                        linewidths=0.4, alpha=0.5)
        ax.clabel(cs, fmt="%.1f m", fontsize=6)
    lim = float(np.nanmax(np.abs(raster))) or 1.0
    im = ax.imshow(np.ma.masked_invalid(raster), cmap="RdBu_r", vmin=-lim, vmax=lim, alpha=0.75, extent=extent,
                   origin="lower", interpolation="nearest")
    ax.figure.colorbar(im, ax=ax, shrink=0.8, label="gap per block (mAh, measured - predicted)")
    if logs is not None:
        for log in log_list(logs):
            if getattr(log, "pose_xyh", None) is not None:
                ax.plot(log.pose_xyh[:, 0], log.pose_xyh[:, 1], color="k", lw=0.6, alpha=0.6)
    r0, r1, c0, c1, gap = max(blocks, key=lambda b: abs(b[4]))
    size, (x0, y0) = terrain.cell_size_m, terrain.origin_xy_m
    margin = 2.0 * max(size * (r1 - r0 + 1), size * (c1 - c0 + 1))  # two blocks around the blocks met
    ax.set_xlim(max(xmin, x0 + size * min(b[2] for b in blocks) - margin),
                min(xmax, x0 + size * (max(b[3] for b in blocks) + 1) + margin))
    ax.set_ylim(max(ymin, y0 + size * min(b[0] for b in blocks) - margin),
                min(ymax, y0 + size * (max(b[1] for b in blocks) + 1) + margin))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"gap on the map: {len(blocks)} blocks; largest {fmt_number(gap, 3)} mAh at cells "
                 f"({r0}-{r1}, {c0}-{c1})", fontsize=10)
