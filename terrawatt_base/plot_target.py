"""Where a figure goes: a PNG file the plotting function writes, or the caller's matplotlib axes.

Every figure function of terrawatt takes an optional positional ``path`` and a keyword
``ax=``: one Axes for a single-panel figure, a sequence of them (one per panel, as
``Figure.subplots`` returns them) for a figure of several panels — so every answer's
``plot(path=None, *, ax=None)`` reads the same; exactly one of
the two is given. With ``path`` the function makes its own figure, saves it atomically and
returns the path; with ``ax`` it draws into the caller's axes, writes nothing,
leaves the caller's figure layout alone and returns the axes it drew into, so figures can
be composed. The checks here make that rule read the same in every module, and
:func:`new_figure` makes the figure of the ``path`` route: matplotlib's object API on an Agg
canvas, never pyplot, so a library figure neither changes the user's backend
(``matplotlib.use``) nor adds to pyplot's figures, and needs no display. The figure is then
written by :func:`terrawatt_base.atomic.save_figure`; nothing needs closing.

Example
-------
>>> from matplotlib.figure import Figure
>>> ax = Figure().subplots()
>>> check_plot_target(None, ax) is None  # draw into ax
True
>>> len(check_axes(Figure().subplots(1, 2), 2, what="histogram, exceedance"))
2
>>> fig, (left, right) = new_figure((8.0, 3.0), 1, 2, sharey=True)
>>> fig.get_size_inches().tolist(), type(fig.canvas).__name__
([8.0, 3.0], 'FigureCanvasAgg')
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import check_output_path
from .errors import InvalidParameterError

__all__ = ["check_plot_target", "check_ax", "check_axes", "new_figure"]


def check_plot_target(path: Any, ax: Any) -> Path | None:
    """The checked output path, or ``None`` when the figure is to be drawn into ``ax``.

    Call it before any work, so a bad path is refused before anything is drawn.

    Parameters
    ----------
    path : str, os.PathLike or None
        The PNG file to write.
    ax : matplotlib Axes, sequence of them, or None
        The caller's axes (checked by :func:`check_ax` / :func:`check_axes`, not here).

    Returns
    -------
    pathlib.Path or None

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax`` given; ``path`` not a file name, a
        directory, or under a file (:func:`terrawatt_base.atomic.check_output_path`).
    """
    if path is None and ax is None:
        raise InvalidParameterError(
            "give either path (a PNG file to write) or ax= (matplotlib axes to draw into), got neither")
    if path is not None and ax is not None:
        raise InvalidParameterError(
            "give either path or ax=, not both: with ax= the figure is drawn into your axes and "
            f"nothing is written (got path={str(path)!r:.80})")
    if ax is not None:
        return None
    if not isinstance(path, (str, os.PathLike)):
        raise InvalidParameterError(f"path must be a file name, got {type(path).__name__!r}")
    return check_output_path(path, "path")


def check_ax(ax: Any, name: str = "ax") -> Any:
    """``ax`` if it is a matplotlib :class:`~matplotlib.axes.Axes`.

    Raises
    ------
    InvalidParameterError
        Anything else (e.g. a figure, or an array of axes given for one panel).
    """
    from matplotlib.axes import Axes

    if not isinstance(ax, Axes):
        raise InvalidParameterError(f"{name} must be a matplotlib Axes, got {type(ax).__name__!r}")
    return ax


def check_axes(axes: Any, n: int, *, what: str = "", name: str = "ax") -> tuple[Any, ...]:
    """``axes`` as a tuple of ``n`` matplotlib Axes.

    A sequence, a nested list or an array of axes (as ``Figure.subplots`` returns them) is
    read in row-major order.

    Parameters
    ----------
    axes : sequence or ndarray of matplotlib Axes
    n : int
        How many panels the figure has.
    what : str
        What the panels are, in order (e.g. ``"left, right"``), for the message.
    name : str
        The keyword, for messages.

    Raises
    ------
    InvalidParameterError
        Not a sequence of Axes, or not ``n`` of them.
    """
    from matplotlib.axes import Axes

    panels = f"{n} matplotlib Axes" + (f" ({what})" if what else "")
    if isinstance(axes, (Axes, str, bytes)) or not hasattr(axes, "__len__"):
        raise InvalidParameterError(f"{name} must be a sequence of {panels}, got {type(axes).__name__!r}")
    flat = tuple(np.asarray(axes, dtype=object).ravel())
    if len(flat) != n:
        raise InvalidParameterError(f"{name} must hold {panels}, got {len(flat)}")
    for k, ax in enumerate(flat):
        check_ax(ax, f"{name}[{k}]")
    return flat


def new_figure(figsize: tuple[float, float], nrows: int = 1, ncols: int = 1, **subplots_kw: Any) -> tuple[Any, Any]:
    """A new figure for a file and its axes: ``Figure(figsize=...)`` on an Agg canvas, no pyplot.

    The one way a terrawatt function makes the figure it writes to ``path``: the user's
    matplotlib backend and pyplot's list of open figures are left alone, and the figure goes
    with its last reference (nothing to close).

    Parameters
    ----------
    figsize : (float, float)
        Width and height in inches.
    nrows, ncols : int
        The grid of axes.
    **subplots_kw
        Passed to :meth:`matplotlib.figure.Figure.subplots` (``sharex``, ``squeeze``, ...).

    Returns
    -------
    (matplotlib.figure.Figure, Axes or ndarray of Axes)
        The figure and what ``Figure.subplots`` returns.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(nrows, ncols, **subplots_kw)
