"""Legs of the adaptive loop: cutting a route into legs and predicting the energy of each."""

from __future__ import annotations

import numpy as np

from terrain import TerrainMap

from ..learned_cost import LearnedEnergyModel

__all__ = ["split_polyline", "cut_at_position", "LegPredictor"]


def split_polyline(wp: np.ndarray, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The first ``length_m`` of a polyline and the rest (sharing the cut point).

    Examples
    --------
    >>> head, tail = split_polyline(np.array([[0.0, 0.0], [10.0, 0.0]]), 4.0)
    >>> head.tolist(), tail.tolist()
    ([[0.0, 0.0], [4.0, 0.0]], [[4.0, 0.0], [10.0, 0.0]])
    """
    seg = np.hypot(*np.diff(wp, axis=0).T)
    cum = np.concatenate(([0.0], np.cumsum(seg)))
    if cum[-1] <= length_m + 1e-9:
        return wp, wp[-1:]
    k = int(np.searchsorted(cum, length_m, side="right"))  # cut inside segment k-1
    f = (length_m - cum[k - 1]) / seg[k - 1]
    cut = wp[k - 1] + f * (wp[k] - wp[k - 1])
    head = np.vstack([wp[:k], cut])
    tail = np.vstack([cut, wp[k:]])
    if np.hypot(*(head[-1] - head[-2])) < 1e-9:
        head = head[:-1]
    if np.hypot(*(tail[1] - tail[0])) < 1e-9:
        tail = tail[1:]
    return head, tail


def cut_at_position(wp: np.ndarray, xy_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A polyline cut where it passes closest to ``xy_m``: the part driven and the rest (sharing the cut point).

    The closest point over all segments (the first one on ties); a robot that drove a leg of
    the route stands at (or near) its end, which this finds again from the pose alone.

    Examples
    --------
    >>> head, tail = cut_at_position(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]]), np.array([6.0, 0.3]))
    >>> head.tolist(), tail.tolist()
    ([[0.0, 0.0], [6.0, 0.0]], [[6.0, 0.0], [10.0, 0.0], [10.0, 5.0]])
    """
    wp = np.asarray(wp, dtype=np.float64)
    p = np.asarray(xy_m, dtype=np.float64)
    if len(wp) < 2:
        return wp.copy(), wp.copy()
    a, d = wp[:-1], np.diff(wp, axis=0)
    len2 = np.einsum("ij,ij->i", d, d)
    f = np.clip(np.einsum("ij,ij->i", p - a, d) / np.where(len2 > 0, len2, 1.0), 0.0, 1.0)
    q = a + f[:, None] * d
    k = int(np.argmin(np.hypot(*(q - p).T)))
    cut = q[k]
    head = np.vstack([wp[: k + 1], cut])
    tail = np.vstack([cut, wp[k + 1:]])
    if len(head) >= 2 and np.hypot(*(head[-1] - head[-2])) < 1e-9:
        head = head[:-1]
    if len(tail) >= 2 and np.hypot(*(tail[1] - tail[0])) < 1e-9:
        tail = tail[1:]
    return head, tail


class LegPredictor:
    """Predicted energy (J) of legs driven rest to rest with the models in use now.

    Prices the stop-turn-go profile of each leg (:meth:`LearnedEnergyModel.predict_route_energy_j`)
    at ``speed_mps``, sampled every ``dt_s``; a route is cut into legs of ``leg_length_m``.
    """

    def __init__(self, learned: LearnedEnergyModel, terrain: TerrainMap, *, speed_mps: float,
                 leg_length_m: float, dt_s: float) -> None:
        self.learned = learned
        self.terrain = terrain
        self.speed_mps = speed_mps
        self.leg_length_m = leg_length_m
        self.dt_s = dt_s

    def leg(self, waypoints: np.ndarray, heading: float | None) -> float:
        """Energy of driving ``waypoints`` (one leg, rest to rest) from ``heading``."""
        if len(waypoints) < 2 or not np.any(np.hypot(*np.diff(waypoints, axis=0).T) > 0):
            return 0.0
        return self.learned.predict_route_energy_j(self.terrain, waypoints, self.speed_mps,
                                                   start_heading_rad=heading, dt_s=self.dt_s)

    def legs(self, waypoints: np.ndarray, heading: float | None) -> list[float]:
        """Energy of each leg of a route driven the way the loop does: leg by leg, stopping at
        each leg's end."""
        energies, rest = [], np.asarray(waypoints, dtype=np.float64)
        while len(rest) >= 2:
            leg, rest = split_polyline(rest, self.leg_length_m)
            energies.append(self.leg(leg, heading))
            d = np.diff(leg, axis=0)
            d = d[np.hypot(d[:, 0], d[:, 1]) > 0]
            if len(d):
                heading = float(np.arctan2(d[-1, 1], d[-1, 0]))
        return energies
