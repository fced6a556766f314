"""Grid: the georeferencing value object shared by maps, registries and edge costs."""

from __future__ import annotations

import numpy as np
import pytest

from terrain import GridMismatchError, InvalidParameterError, OutOfBoundsError
from terrain.grid import Grid


def test_conversions_follow_the_documented_convention() -> None:
    g = Grid((4, 5), 2.0, (10.0, 20.0))
    assert g.bounds == (10.0, 20.0, 20.0, 28.0) and g.n_cells == 20
    assert g.rowcol(10.0, 20.0) == (0, 0)
    assert g.rowcol(20.0, 28.0) == (3, 4)  # far edges map inside
    rows, cols = g.rowcol(np.array([11.0, 19.9]), np.array([21.0, 27.0]))
    assert rows.tolist() == [0, 3] and cols.tolist() == [0, 4]
    x, y = g.xy(rows, cols)
    assert np.allclose(x, [11.0, 19.0]) and np.allclose(y, [21.0, 27.0])
    xs, ys = g.cell_centres()
    assert xs.tolist() == [11.0, 13.0, 15.0, 17.0, 19.0] and ys.tolist() == [21.0, 23.0, 25.0, 27.0]
    assert g.contains(9.99, 20.0) is False
    with pytest.raises(OutOfBoundsError, match="outside the map bounds"):
        g.rowcol(9.0, 21.0)
    with pytest.raises(OutOfBoundsError):
        g.rowcol(np.nan, 21.0)


def test_value_semantics() -> None:
    a = Grid((3, 3), 1.0, (0.0, 0.0))
    b = Grid((3, 3), 1, (0, 0))  # normalised to floats and ints
    assert a == b and hash(a) == hash(b)
    a.check_same(b)
    with pytest.raises(GridMismatchError, match="the registry is on Grid"):
        a.check_same(Grid((3, 3), 0.5), "the registry")


def test_from_bounds() -> None:
    g = Grid.from_bounds((2, 4), (0.0, 0.0, 8.0, 4.0))
    assert g == Grid((2, 4), 2.0, (0.0, 0.0))
    with pytest.raises(InvalidParameterError, match="expected square cells"):
        Grid.from_bounds((2, 4), (0.0, 0.0, 8.0, 8.0))


@pytest.mark.parametrize(
    "args, pattern",
    [
        (((0, 3), 1.0), r"shape\[0\] must be >= 1"),
        (((2.5, 3), 1.0), r"shape\[0\] must be an integer"),
        (((3,), 1.0), r"shape must be \(rows, cols\)"),
        (((3, 3), "1.0"), r"cell_size_m must be a real number, got '1.0' \(str\)"),
        (((3, 3), -1.0), r"cell_size_m must be > 0"),
        (((3, 3), 1e308), r"no finite far corner"),
        (((3, 3), 1.0, (np.nan, 0.0)), r"origin_xy_m\[0\] must be finite"),
        (((3, 3), 1.0, 5.0), r"origin_xy_m must be \(x, y\)"),
    ],
)
def test_bad_grids_name_the_parameter(args, pattern) -> None:
    with pytest.raises(InvalidParameterError, match=pattern):
        Grid(*args)
