"""What every answer shares when it is printed and saved: its files written into a folder, its tables, its numbers."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from .checks import check_choice
from .figure_file import FIGURE_ERRORS, draw_figure

__all__ = ["fmt_fixed", "markdown_table", "write_answer"]


def fmt_fixed(value: float | None, digits: int = 1, *, missing: str = "–") -> str:
    """``value`` with ``digits`` decimals, or ``missing`` for None, NaN and infinities (a table's empty cell).

    Examples
    --------
    >>> fmt_fixed(2.345), fmt_fixed(2.345, 2), fmt_fixed(float("nan")), fmt_fixed(None, missing="-")
    ('2.3', '2.35', '–', '-')
    """
    return missing if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[Any]], *, left: int | None = None) -> list[str]:
    """The lines of a markdown table: ``header``, its rule, a line per row (each cell as ``str``).

    Parameters
    ----------
    header : sequence of str
        The column titles.
    rows : iterable of sequences
        The cells of each row, as many as ``header``.
    left : int, optional
        How many leading columns are text (``---``); the others are numbers, aligned right
        (``---:``). Default: every column ``---``.

    Returns
    -------
    list of str

    Examples
    --------
    >>> markdown_table(["run", "error %"], [["a", fmt_fixed(1.25)]], left=1)
    ['| run | error % |', '|---|---:|', '| a | 1.2 |']
    """
    n_left = len(header) if left is None else left
    rule = "|" + "|".join("---" if k < n_left else "---:" for k in range(len(header))) + "|"
    return [_row(header), rule, *(_row(r) for r in rows)]


def _row(cells: Sequence[Any]) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def write_answer(
    out_dir: str | os.PathLike[str],
    files: Mapping[str, Callable[[Path], Path | None]],
    figures: Mapping[str, Callable[[Path], Any]] | None = None,
    *,
    on_figure_error: str = "warn",
) -> list[Path]:
    """Write an answer's files into ``out_dir`` (created), then its figures; return what was written.

    Each writer of ``files`` is called with its path in ``out_dir`` and returns the path it wrote, or
    None when it had nothing to write (left out). The figures come last: each draw is called with its
    path through :func:`~terrawatt_base.figure_file.draw_figure`, so one that fails warns and is left
    out (``on_figure_error="warn"``) and the files before it stand.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The folder (created, parents too).
    files : mapping of str to callable
        Each file's name (or path relative to ``out_dir``) and its writer, in the order to write.
    figures : mapping of str to callable, optional
        Each figure's name and its draw, written after the files.
    on_figure_error : {"warn", "raise"}
        What a figure that fails does (checked before anything is written).

    Returns
    -------
    list of pathlib.Path
        In the order written.

    Raises
    ------
    UnknownNameError
        ``on_figure_error`` not one of :data:`~terrawatt_base.figure_file.FIGURE_ERRORS`.

    Examples
    --------
    >>> import tempfile
    >>> folder = tempfile.TemporaryDirectory()
    >>> [p.name for p in write_answer(folder.name, {"a.txt": lambda p: p.write_text("a") and p,
    ...                                            "b.txt": lambda p: None})]
    ['a.txt']
    >>> folder.cleanup()
    """
    check_choice("on_figure_error", on_figure_error, FIGURE_ERRORS)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [p for p in (write(out / name) for name, write in files.items()) if p is not None]
    for name, draw in (figures or {}).items():
        drawn = draw_figure(out / name, lambda d=draw, p=out / name: d(p), on_error=on_figure_error)
        if drawn is not None:
            written.append(drawn)
    return written
