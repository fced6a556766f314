"""Tests of planner.missions.tracking: which route segment each pose is on."""

from __future__ import annotations

import numpy as np

from planner.missions.tracking import segments_by_pose


def test_poses_along_an_l_route_are_assigned_to_their_segments():
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    xy = np.vstack([np.column_stack([np.arange(0.0, 10.5, 1.0), np.zeros(11)]),
                    np.column_stack([np.full(10, 10.0), np.arange(1.0, 10.5, 1.0)])])
    idx, reached = segments_by_pose(xy, pts, tol_m=0.25)
    assert reached == 2
    assert idx[:10].tolist() == [0] * 10  # before the corner
    assert idx[11:].tolist() == [1] * 10  # after it


def test_a_robot_that_stops_short_reaches_no_segment_end():
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    xy = np.column_stack([np.arange(0.0, 6.0, 1.0), np.zeros(6)])
    idx, reached = segments_by_pose(xy, pts, tol_m=0.25)
    assert reached == 0 and not idx.any()
