"""Tests of planner.missions.legs: split_polyline cuts a polyline at a length along it."""

from __future__ import annotations

import numpy as np

from planner.missions.legs import split_polyline


def test_a_cut_inside_a_segment_is_shared_by_both_parts():
    wp = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    head, tail = split_polyline(wp, 12.0)
    np.testing.assert_allclose(head, [[0.0, 0.0], [10.0, 0.0], [10.0, 2.0]])
    np.testing.assert_allclose(tail, [[10.0, 2.0], [10.0, 10.0]])


def test_a_cut_on_a_vertex_repeats_no_point():
    wp = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    head, tail = split_polyline(wp, 10.0)
    np.testing.assert_allclose(head, [[0.0, 0.0], [10.0, 0.0]])
    np.testing.assert_allclose(tail, [[10.0, 0.0], [10.0, 10.0]])


def test_a_length_beyond_the_end_keeps_the_whole_polyline():
    wp = np.array([[0.0, 0.0], [3.0, 4.0]])
    head, tail = split_polyline(wp, 6.0)
    assert head is wp and tail.tolist() == [[3.0, 4.0]]
