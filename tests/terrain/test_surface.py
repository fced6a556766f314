"""terrain.surface: slope, aspect and gradients of an elevation raster on planes with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from terrain import flat_map, ramp_map, surface_layers
from terrain.surface import SURFACE_LAYERS


def test_surface_layers_are_named_in_order():
    assert SURFACE_LAYERS == ("slope", "aspect", "grad_x", "grad_y")
    assert tuple(surface_layers(np.zeros((2, 2)), 1.0)) == SURFACE_LAYERS


def test_a_flat_plane_has_no_slope_and_no_gradient():
    layers = surface_layers(np.full((4, 5), 12.5), 2.0)
    for name in ("slope", "grad_x", "grad_y"):
        assert np.array_equal(layers[name], np.zeros((4, 5))), name
        assert layers[name].dtype == np.float64


def test_an_eastward_ramp_everywhere_including_the_edges():
    cell = 0.5
    z = np.add.outer(np.zeros(3), 0.1 * cell * np.arange(6))  # rises 0.1 m per metre along +x
    layers = surface_layers(z, cell)
    np.testing.assert_allclose(layers["grad_x"], 0.1, rtol=1e-12)
    np.testing.assert_allclose(layers["grad_y"], 0.0, atol=1e-15)
    np.testing.assert_allclose(layers["slope"], math.atan(0.1), rtol=1e-12)
    # downslope points to -x
    np.testing.assert_allclose(np.abs(layers["aspect"]), math.pi, rtol=1e-12)


def test_a_northward_ramp_faces_south_and_a_45_degree_diagonal():
    z = np.add.outer(2.0 * np.arange(4), np.zeros(3))  # rows grow with y: rises 1 m per metre along +y
    layers = surface_layers(z, 2.0)
    np.testing.assert_allclose(layers["grad_y"], 1.0)
    np.testing.assert_allclose(layers["slope"], math.pi / 4)
    np.testing.assert_allclose(layers["aspect"], -math.pi / 2)  # downslope is -y
    diag = surface_layers(np.add.outer(np.arange(3.0), np.arange(3.0)), 1.0)  # z = x + y
    np.testing.assert_allclose(diag["slope"], math.atan(math.sqrt(2.0)))
    np.testing.assert_allclose(diag["aspect"], -3 * math.pi / 4)


def test_the_cell_size_scales_the_gradient():
    z = np.add.outer(np.zeros(2), np.arange(3.0))
    assert surface_layers(z, 1.0)["grad_x"][0, 0] == pytest.approx(1.0)
    assert surface_layers(z, 4.0)["grad_x"][0, 0] == pytest.approx(0.25)


def test_terrain_maps_derive_their_layers_with_this_function():
    for tmap in (flat_map((6, 7), 0.5), ramp_map((6, 7), 0.5, grade=0.2, axis="y")):
        layers = surface_layers(tmap.elevation_m, tmap.cell_size_m)
        for name in SURFACE_LAYERS:
            assert np.array_equal(tmap[name], layers[name]), name
