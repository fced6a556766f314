"""A report's figure file: drawn, or a FigureWarning when it cannot be, so the results written before it stand."""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from pathlib import Path

from .checks import check_choice
from .errors import FigureWarning

__all__ = ["FIGURE_ERRORS", "draw_figure"]

#: What :func:`draw_figure` does when a figure fails: raise the error, or warn and go on.
FIGURE_ERRORS = ("warn", "raise")


def draw_figure(path: str | os.PathLike[str], draw: Callable[[], Path], *, on_error: str = "warn") -> Path | None:
    """Call ``draw`` (which writes the figure ``path``) and return what it returns.

    A figure is the last file of a report: with ``on_error="warn"`` any failure of ``draw``
    becomes a :class:`~terrawatt_base.errors.FigureWarning` ``"could not draw PATH: Error:
    message"`` and None is returned, so the results already written stand.

    Raises
    ------
    UnknownNameError
        ``on_error`` not one of :data:`FIGURE_ERRORS`.
    Exception
        With ``on_error="raise"``, whatever ``draw`` raises.

    Examples
    --------
    >>> import warnings
    >>> def broken():
    ...     raise RuntimeError("no canvas")
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     draw_figure("route.png", broken) is None, str(caught[0].message)
    (True, 'could not draw route.png: RuntimeError: no canvas')
    """
    check_choice("on_error", on_error, FIGURE_ERRORS)
    try:
        return draw()
    except Exception as exc:  # noqa: BLE001 - any failure of a figure: a warning, never lost results
        if on_error == "raise":
            raise
        warnings.warn(f"could not draw {path}: {type(exc).__name__}: {exc}", FigureWarning, stacklevel=2)
        return None
