"""Figures of a diagnosis: effect ranking, waterfall, and :func:`plot_diagnosis`, which draws every figure.

Each figure is a public function. Where it goes (the rule of every terrawatt figure,
:mod:`terrawatt_base.plot_target`): give exactly one of ``path`` or ``ax=``: one matplotlib Axes for a single-panel figure (the
effect ranking, the gap map), a sequence of one Axes per panel for the others.
With ``path`` the function makes its own figure, writes one PNG through
:func:`terrawatt_base.atomic.save_figure` and returns its path; the output path is checked before
anything is drawn. With ``ax`` it draws into the caller's axes, writes nothing,
leaves the caller's figure layout alone (no ``tight_layout``) and returns the axes (a tuple
for several panels), so figures can be composed. A figure's suptitle belongs to the figure it makes
and is drawn only with ``path``; with ``ax`` it is left out (the panels keep their own
titles, labels and legends). A colour bar is attached to ``ax.figure``, beside ``ax``.
:func:`plot_diagnosis` writes a folder of figures and stays path-based.

The figures of where the gap lies (residual over time, by regime, on the map) are in
:mod:`energy.diagnosis.plots_gap` and re-exported here. :func:`plot_diagnosis` *skips* a
figure whose data is missing (no poses or no map: no map figure) and says why in
:attr:`DiagnosisFigures.skipped`; called on its own, such a figure raises
:class:`~terrawatt_base.errors.DataError` with that reason.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base import plot_target
from terrawatt_base.atomic import check_output_path, save_figure
from terrawatt_base.checks import check_choice, check_int, fmt_number
from terrawatt_base.errors import DataError, FigureWarning, InvalidParameterError
from terrawatt_base.plot_target import check_ax, check_axes, check_plot_target

from .plots_gap import (
    REGIME_PANELS,
    checked_diagnosis,
    log_list,
    missing_map_reason,
    missing_regimes_reason,
    plot_gap_by_regime,
    plot_gap_map,
    plot_residual_time,
)
from .regimes import check_terrain

__all__ = [
    "FIGURES",
    "REGIME_PANELS",
    "DiagnosisFigures",
    "plot_residual_time",
    "plot_gap_by_regime",
    "plot_gap_map",
    "plot_effect_ranking",
    "plot_waterfall",
    "plot_diagnosis",
    "skipped_figures",
]

#: Figure names of :func:`plot_diagnosis` and their file names, in drawing order.
FIGURES: dict[str, str] = {
    "residual_time": "residual_time.png",
    "gap_by_regime": "gap_by_regime.png",
    "gap_map": "gap_map.png",
    "effect_ranking": "effect_ranking.png",
    "waterfall": "waterfall.png",
}

_KIND_COLOURS = {"physics": "#3182bd", "parameter": "#31a354", "measurement": "#756bb1", "learned": "#969696"}
_WATERFALL_PANELS = (("error_pct", "whole-set charge error (%)", "#de2d26"),
                     ("section_error_pct", "8 s section error (%)", "#fd8d3c"),
                     ("rmse", "RMSE (A)", "#3182bd"))
_NO_RANKING = "no effect ranking: no candidate effect was scored (every one was skipped for these data)"


# ----------------------------------------------------------------- effect ranking
def plot_effect_ranking(diagnosis: Any, path: str | os.PathLike[str] | None = None, *, ax: Any = None,
                        max_effects: int = 20, dpi: int = 110) -> Path | Any:
    """The effect ranking: what each candidate adds to the chosen effects above it (held-out, 95 % interval) and its shrink alone.

    Horizontal bars, best first, coloured by kind; effects the greedy selection chose are
    marked with their order, the learned correction is labelled as such.

    Parameters
    ----------
    diagnosis : Diagnosis
    path : path-like, optional
        PNG file to write (or give ``ax``).
    ax : matplotlib Axes, optional
        Draw into these axes instead of writing a file.
    max_effects : int
        Draw the best this many candidates (>= 1).
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Not a Diagnosis; both or neither of ``path`` and ``ax``; a bad ``path`` (checked
        before drawing), ``ax`` or ``max_effects``.
    DataError
        No candidate was scored.
    """
    diagnosis = checked_diagnosis(diagnosis)
    target = check_plot_target(path, ax)
    if target is None:
        ax = check_ax(ax)
    max_effects = check_int("max_effects", max_effects, low=1)
    dpi = check_int("dpi", dpi, low=10, high=1200)
    if not diagnosis.current.ranking:
        raise DataError(_NO_RANKING)
    ranking = list(diagnosis.current.ranking[:max_effects])
    if target is None:
        _draw_ranking(ax, diagnosis, ranking)
        return ax

    fig, ax = plot_target.new_figure((9, 0.38 * len(ranking) + 1.8))
    _draw_ranking(ax, diagnosis, ranking)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_ranking(ax: Any, diagnosis: Any, ranking: Sequence[Any]) -> None:
    """The bars of :func:`plot_effect_ranking`, drawn into ``ax``."""
    from matplotlib.patches import Patch

    order = {n: k + 1 for k, n in enumerate(diagnosis.current.chosen)}
    y = np.arange(len(ranking))
    shrink = np.array([s.added_pct for s in ranking])
    lo = np.array([s.added_interval_pct[0] for s in ranking])
    hi = np.array([s.added_interval_pct[1] for s in ranking])
    alone = np.array([s.shrink_pct for s in ranking])
    colours = [_KIND_COLOURS.get(s.kind, "#969696") for s in ranking]
    bars = ax.barh(y, shrink, color=colours, alpha=0.85)
    for bar, s in zip(bars, ranking):
        if s.name in order:
            bar.set_edgecolor("k")
            bar.set_linewidth(1.6)
        if s.kind == "learned":
            bar.set_hatch("//")
    ax.errorbar(shrink, y, xerr=[np.maximum(shrink - lo, 0.0), np.maximum(hi - shrink, 0.0)], fmt="none", ecolor="k",
                elinewidth=1.0, capsize=3)
    ax.plot(alone, y, "o", mfc="none", mec="k", ms=5, label="alone")
    names = []
    for s in ranking:
        name = f"{s.name} (learned, not physics)" if s.kind == "learned" else s.name
        names.append(f"* {name} [chosen {order[s.name]}]" if s.name in order else name)
    ax.set_yticks(y, names, fontsize=8)
    ax.invert_yaxis()
    ax.axvline(0.0, color="k", lw=0.6)
    ax.set_xlabel(f"held-out shrink of the squared current gap (points of %), split by {diagnosis.settings.split}: "
                  "what each adds to the chosen effects above it (95 % bootstrap interval); o: the effect alone", fontsize=8)
    kinds = sorted({s.kind for s in ranking})
    handles = [Patch(facecolor=_KIND_COLOURS.get(k, "#969696"), label=k) for k in kinds]
    ax.legend(handles=handles + ax.get_legend_handles_labels()[0], fontsize=8, loc="lower right")
    n_ranked = len(diagnosis.current.ranking)
    more = f" (best {len(ranking)} of {n_ranked})" if n_ranked > len(ranking) else ""
    chosen = ", ".join(diagnosis.current.chosen) if diagnosis.current.chosen else "none"
    ax.set_title(f"candidate effects, added greedily{more}; chosen: {chosen}", fontsize=10)
    ax.grid(axis="x", alpha=0.3)


# ----------------------------------------------------------------- waterfall
def plot_waterfall(diagnosis: Any, path: str | os.PathLike[str] | None = None, *,
                   ax: Sequence[Any] | None = None, dpi: int = 110) -> Path | tuple[Any, ...]:
    """The held-out waterfall: charge error (%), 8 s section error (%) and RMSE (A) after each added effect.

    Parameters
    ----------
    diagnosis : Diagnosis
    path : path-like, optional
        PNG file to write (or give ``ax``).
    ax : sequence of 3 matplotlib Axes, optional
        Charge error, section error, RMSE: draw into these instead of writing a file.
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or tuple of 3 Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Not a Diagnosis; both or neither of ``path`` and ``ax``; a bad ``path`` (checked
        before drawing); not 3 axes.
    """
    diagnosis = checked_diagnosis(diagnosis)
    target = check_plot_target(path, ax)
    dpi = check_int("dpi", dpi, low=10, high=1200)
    steps = diagnosis.current.waterfall
    if target is None:
        panels = check_axes(ax, 3, what="charge error, section error, RMSE")
        _draw_waterfall(panels, steps)
        return panels

    fig, panels = plot_target.new_figure((4.0 * 3, 3.6 + 0.12 * len(steps)), 1, 3)
    _draw_waterfall(panels, steps)
    held = "held-out runs" if diagnosis.settings.split == "runs" else "held-out blocks"
    fig.suptitle(f"how far the gap shrinks on {held}, effect by effect", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_waterfall(panels: Sequence[Any], steps: Sequence[Any]) -> None:
    """The three panels of :func:`plot_waterfall`, drawn into ``panels``."""
    x = np.arange(len(steps))
    for ax, (attr, title, colour) in zip(panels, _WATERFALL_PANELS):
        vals = np.array([getattr(w, attr) for w in steps], dtype=float)
        ax.bar(x, vals, color=colour, alpha=0.85)
        for k, v in enumerate(vals):
            ax.annotate(fmt_number(float(v), 3), (k, v), ha="center", va="bottom" if v >= 0 else "top", fontsize=8)
        ax.set_xticks(x, [w.label for w in steps], rotation=30, ha="right", fontsize=8)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_title(title, fontsize=10)
        ax.margins(y=0.15)
        ax.grid(axis="y", alpha=0.3)


# ----------------------------------------------------------------- all of them
@dataclass(frozen=True)
class DiagnosisFigures:
    """What :func:`plot_diagnosis` drew.

    Attributes
    ----------
    written : dict of str to pathlib.Path
        Figure name (:data:`FIGURES`) -> written file.
    skipped : dict of str to str
        Figure name -> why its data is missing.
    failed : dict of str to str
        Figure name -> the error that stopped it (only with ``on_error="warn"``).
    """

    written: dict[str, Path] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)

    def __str__(self) -> str:
        lines = [f"{name}: {path}" for name, path in self.written.items()]
        lines += [f"{name}: skipped, {why}" for name, why in self.skipped.items()]
        lines += [f"{name}: failed, {why}" for name, why in self.failed.items()]
        return "\n".join(lines)


def skipped_figures(diagnosis: Any) -> dict[str, str]:
    """The figures of :func:`plot_diagnosis` whose data is missing, and why (figure name -> reason).

    Parameters
    ----------
    diagnosis : Diagnosis
        With the logs and the map it ran on (:attr:`Diagnosis.logs`, :attr:`Diagnosis.terrain`).

    Returns
    -------
    dict of str to str
        In the order of :data:`FIGURES`; empty when every figure can be drawn.

    Raises
    ------
    InvalidParameterError
        Not a Diagnosis, not a TerrainMap, logs that are not InteractionLogs.
    """
    diagnosis = checked_diagnosis(diagnosis)
    terrain = check_terrain(diagnosis.terrain)
    logs = list(diagnosis.logs) or None
    skipped: dict[str, str] = {}
    if logs is None:
        skipped["residual_time"] = "no residual over time: no logs given"
    why = missing_regimes_reason(diagnosis)
    if why:
        skipped["gap_by_regime"] = why
    why = missing_map_reason(diagnosis, terrain, logs)
    if why:
        skipped["gap_map"] = why
    if not diagnosis.current.ranking:
        skipped["effect_ranking"] = _NO_RANKING
    return skipped


def plot_diagnosis(diagnosis: Any, directory: str | os.PathLike[str], *, predictions: Any = None,
                   figures: Sequence[str] | None = None, max_runs: int = 4, on_error: str = "raise",
                   dpi: int = 110) -> DiagnosisFigures:
    """Draw every figure of a diagnosis into ``directory`` (file names :data:`FIGURES`).

    It draws the logs and the map the diagnosis ran on (:attr:`Diagnosis.logs`, :attr:`Diagnosis.terrain`).
    A figure whose data is missing is skipped with its reason: the residual over time
    without logs; the map without a map or poses. Without ``predictions`` the
    residual is that of the model as given (``diagnosis.corrected_model.base``), and the
    corrected model's (fitted on all logs: in-sample) is drawn dashed beside it.

    Parameters
    ----------
    diagnosis : Diagnosis
    directory : path-like
        Folder to write into (created when missing).
    predictions : sequence of array_like (N, 2), optional
        Predictions of the model as given, per log.
    figures : sequence of str, optional
        Names from :data:`FIGURES` (default all).
    max_runs : int
        Panels of the residual-over-time figure.
    on_error : {"raise", "warn"}
        A figure that fails while drawing raises, or warns (:class:`~terrawatt_base.errors.FigureWarning`)
        and is listed in :attr:`DiagnosisFigures.failed`. Bad arguments always raise.
    dpi : int

    Returns
    -------
    DiagnosisFigures

    Raises
    ------
    InvalidParameterError
        Not a Diagnosis; ``directory`` (or a figure's file in it) of the wrong kind, checked
        before drawing; bad ``figures``, ``max_runs``, ``on_error`` or ``dpi``.
    UnknownNameError
        A figure name not in :data:`FIGURES`, or an unknown ``on_error``.
    """
    diagnosis = checked_diagnosis(diagnosis)
    terrain = check_terrain(diagnosis.terrain)
    logs = list(diagnosis.logs) or None
    check_choice("on_error", on_error, ("raise", "warn"))
    max_runs = check_int("max_runs", max_runs, low=1, high=8)
    dpi = check_int("dpi", dpi, low=10, high=1200)
    if figures is None:
        names = list(FIGURES)
    elif isinstance(figures, (str, bytes)) or not isinstance(figures, Sequence):
        raise InvalidParameterError(f"figures must be None or a sequence of figure names, got {figures!r:.80}")
    else:
        names = [check_choice("figures", n, tuple(FIGURES)) for n in figures]
    folder = check_output_path(directory, "directory", directory=True)
    paths = {n: check_output_path(folder / FIGURES[n], f"directory {str(folder)!r}: {FIGURES[n]}") for n in names}

    skipped = skipped_figures(diagnosis)

    def residual(path: Path) -> Path:
        items = log_list(logs)
        preds, after = predictions, None
        if preds is None:
            model = diagnosis.corrected_model
            base = getattr(model, "base", model)
            preds = [base.predict(log) for log in items]
            after = [model.predict(log) for log in items] if model is not base else None
        return plot_residual_time(items, preds, path, corrected=after, max_runs=max_runs, dpi=dpi)

    draw = {
        "residual_time": residual,
        "gap_by_regime": lambda p: plot_gap_by_regime(diagnosis, p, dpi=dpi),
        "gap_map": lambda p: plot_gap_map(diagnosis, terrain, p, logs=logs, dpi=dpi),
        "effect_ranking": lambda p: plot_effect_ranking(diagnosis, p, dpi=dpi),
        "waterfall": lambda p: plot_waterfall(diagnosis, p, dpi=dpi),
    }
    written: dict[str, Path] = {}
    failed: dict[str, str] = {}
    todo = [n for n in names if n not in skipped]
    if todo:
        folder.mkdir(parents=True, exist_ok=True)
    for name in todo:
        try:
            written[name] = draw[name](paths[name])
        except Exception as exc:  # noqa: BLE001 - with on_error="warn" a failing figure is reported, never fatal
            if on_error == "raise":
                raise
            failed[name] = f"{type(exc).__name__}: {exc}"
            warnings.warn(f"plot_diagnosis: could not draw {name}: {failed[name]}", FigureWarning, stacklevel=2)
    return DiagnosisFigures(written, {n: w for n, w in skipped.items() if n in names}, failed)
