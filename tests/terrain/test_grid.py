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


# ------------------------------------------------------------------ affine transform
def test_the_transform_converts_cells_and_metres_as_rowcol_and_xy_do():
    from affine import Affine

    g = Grid((4, 5), 2.0, (10.0, 20.0))
    assert g.transform == Affine(2.0, 0.0, 10.0, 0.0, 2.0, 20.0)
    assert g.north_up_transform == Affine(2.0, 0.0, 10.0, 0.0, -2.0, 28.0)
    rows, cols = np.meshgrid(np.arange(4), np.arange(5), indexing="ij")
    cx, cy = g.transform @ (cols + 0.5, rows + 0.5)
    assert np.allclose((cx, cy), g.xy(rows, cols))
    # the north-up transform indexes the flipped array: its row 0 is this grid's last row
    nx, ny = g.north_up_transform @ (cols + 0.5, rows + 0.5)
    assert np.allclose((nx, ny), g.xy(3 - rows, cols))
    inv_c, inv_r = ~g.transform @ (cx, cy)
    assert np.array_equal(np.floor(inv_r).astype(int), rows) and np.array_equal(np.floor(inv_c).astype(int), cols)
    assert Grid.from_transform(g.shape, g.transform) == g == Grid.from_transform(g.shape, g.north_up_transform)


def test_the_transform_agrees_with_rasterio():
    rasterio = pytest.importorskip("rasterio", reason="rasterio is in the geo extra")
    g = Grid((6, 3), 0.5, (-1.0, 4.0))
    for r, c in [(0, 0), (5, 2), (2, 1)]:
        assert rasterio.transform.xy(g.transform, r, c) == pytest.approx(g.xy(r, c))
        x, y = g.xy(r, c)
        assert rasterio.transform.rowcol(g.transform, x, y) == (r, c) == g.rowcol(x, y)
        assert rasterio.transform.rowcol(g.north_up_transform, x, y) == (5 - r, c)


@pytest.mark.parametrize(("transform", "match"), [
    ("not affine", "must be an affine.Affine"),
    ("rotated", "rotated or sheared"),
    ("oblong", "square cells"),
])
def test_from_transform_refuses_what_is_not_a_square_grid(transform, match):
    from affine import Affine

    value = {"not affine": (1, 0, 0, 0, -1, 0), "rotated": Affine.rotation(10.0) @ Affine.scale(2.0),
             "oblong": Affine(2.0, 0.0, 0.0, 0.0, -3.0, 0.0)}[transform]
    with pytest.raises(InvalidParameterError, match=match):
        Grid.from_transform((3, 3), value)
