"""The figure of a replayed drive: the per-cell models before and after, the routes, the forecast against the actual.

Where a figure goes follows every terrawatt figure (:mod:`terrawatt_base.plot_target`): exactly
one of ``path`` (a PNG written atomically) or ``ax=`` (four matplotlib Axes drawn into).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.plot_target import check_axes, check_plot_target

__all__ = ["plot_replay"]


def plot_replay(result: Any, path: str | os.PathLike[str] | None = None, *, ax: Sequence[Any] | None = None,
                dpi: int = 90) -> Path | tuple[Any, ...]:
    """Four panels of a :class:`~planner.missions.replay.ReplayResult`: cells by model before and
    after (with the driven path and every route the navigator gave), the remaining energy's
    forecast with its interval at each checkpoint against what the robot then drew, and the
    state of charge.

    Returns
    -------
    Path or tuple of 4 Axes

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; a bad ``path``; not 4 axes.
    """
    target = check_plot_target(path, ax)
    if target is None:
        panels = check_axes(ax, 4, what="models before, models after, remaining energy, state of charge")
        _draw(panels, result)
        return panels
    fig, grid = plot_target.new_figure((11, 9), 2, 2)
    _draw(grid.ravel(), result)
    nav = result.navigator
    fig.suptitle(f"replay: {nav.status if nav.finished else 'under way'}, {len(nav.legs)} checkpoints, "
                 f"{sum(u.accepted for u in nav.updates)} accepted updates")
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi, format="png")


def _draw(panels: Sequence[Any], result: Any) -> None:
    import matplotlib
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    ax = np.asarray(panels, dtype=object).reshape(2, 2)
    nav = result.navigator
    terrain, registry = nav.terrain, nav.registry
    xmin, ymin, xmax, ymax = terrain.bounds
    ext = (xmin, xmax, ymin, ymax)
    ids = np.unique(np.concatenate([np.unique(result.model_map_before), np.unique(result.model_map_after)]))
    palette = matplotlib.colormaps["tab10"].colors
    colours = [palette[i % len(palette)] for i in range(ids.size)]
    cmap, norm = ListedColormap(colours), BoundaryNorm(np.arange(ids.size + 1) - 0.5, ids.size)
    res = nav.result()
    for a, id_map, title in ((ax[0, 0], result.model_map_before, "cells by model, before"),
                             (ax[0, 1], result.model_map_after, "cells by model, after")):
        a.imshow(np.searchsorted(ids, id_map), origin="lower", extent=ext, interpolation="nearest", cmap=cmap,
                 norm=norm)
        a.plot(res.x_m, res.y_m, "c-", lw=1.5, label="driven")
        a.set_title(title)
        a.set_xlabel("x (m)")
        a.set_ylabel("y (m)")
    for k, (_, wp) in enumerate(result.replans):
        ax[0, 1].plot(wp[:, 0], wp[:, 1], "w--" if k == 0 else "y-", lw=1, label="first plan" if k == 0 else
                      ("new routes" if k == 1 else None))
    names = [Patch(color=c, label=f"{int(m)}: {registry.model_record(int(m)).name}")
             for m, c in zip(ids.tolist(), colours) if int(m) in registry.model_ids]
    handles, _ = ax[0, 1].get_legend_handles_labels()
    ax[0, 1].legend(handles=handles + names, loc="upper left", fontsize=7, framealpha=0.85)
    fc = result.forecast
    t = fc["time_s"]
    if t.size:
        lvl = 100 * nav.settings.interval_level
        ax[1, 0].fill_between(t, fc["low_j"] / 3600.0, fc["high_j"] / 3600.0, color="tab:blue", alpha=0.2,
                              label=f"{lvl:.0f} % interval")
        ax[1, 0].plot(t, fc["energy_j"] / 3600.0, "o-", color="tab:blue", ms=3, label="forecast of the rest")
        if np.isfinite(fc["actual_j"]).any():
            ax[1, 0].plot(t, fc["actual_j"] / 3600.0, "k.-", ms=3, label="then actually drawn")
        ax[1, 0].legend(fontsize=8)
    ax[1, 0].set_xlabel("time (s)")
    ax[1, 0].set_ylabel("remaining energy (Wh)")
    ax[1, 1].plot(res.time_s, 100.0 * res.soc)
    ax[1, 1].axhline(nav.battery.min_reserve_pct, color="tab:red", ls="--", label="reserve")
    ax[1, 1].set_xlabel("time (s)")
    ax[1, 1].set_ylabel("state of charge (%)")
    ax[1, 1].legend(fontsize=8)
