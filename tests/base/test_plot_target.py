"""Where a figure goes: exactly one of a path to write or the caller's axes, checked before drawing."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from terrain import InvalidParameterError
from terrawatt_base.plot_target import check_ax, check_axes, check_plot_target


def test_a_path_is_checked_and_returned(tmp_path):
    assert check_plot_target(tmp_path / "a.png", None) == tmp_path / "a.png"
    assert check_plot_target(str(tmp_path / "a.png"), None) == tmp_path / "a.png"
    with pytest.raises(InvalidParameterError, match="is a directory"):
        check_plot_target(tmp_path, None)
    with pytest.raises(InvalidParameterError, match="path must be a file name, got 'int'"):
        check_plot_target(3, None)


def test_axes_mean_no_path(tmp_path):
    ax = Figure().subplots()
    assert check_plot_target(None, ax) is None
    assert list(tmp_path.iterdir()) == []


def test_both_or_neither_is_refused(tmp_path):
    ax = Figure().subplots()
    with pytest.raises(InvalidParameterError, match=r"either path .* or ax=.*got neither"):
        check_plot_target(None, None)
    with pytest.raises(InvalidParameterError, match="either path or axes=, not both"):
        check_plot_target(tmp_path / "a.png", [ax], axes_name="axes")


def test_one_axes():
    fig = Figure()
    ax = fig.subplots()
    assert check_ax(ax) is ax
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'Figure'"):
        check_ax(fig)
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'ndarray'"):
        check_ax(Figure().subplots(1, 2))


def test_several_axes_are_read_in_row_major_order():
    grid = Figure().subplots(2, 2)
    assert check_axes(grid, 4) == (grid[0, 0], grid[0, 1], grid[1, 0], grid[1, 1])
    assert check_axes([[grid[0, 0]], [grid[1, 1]]], 2) == (grid[0, 0], grid[1, 1])
    pair = Figure().subplots(1, 2)
    assert check_axes(list(pair), 2) == tuple(pair)
    with pytest.raises(InvalidParameterError, match=r"axes must hold 3 matplotlib Axes \(a, b, c\), got 2"):
        check_axes(pair, 3, what="a, b, c")
    with pytest.raises(InvalidParameterError, match="must be a sequence of 2 matplotlib Axes, got 'Axes'"):
        check_axes(pair[0], 2)
    with pytest.raises(InvalidParameterError, match=r"axes\[1\] must be a matplotlib Axes, got 'str'"):
        check_axes(np.array([pair[0], "x"], dtype=object), 2)
