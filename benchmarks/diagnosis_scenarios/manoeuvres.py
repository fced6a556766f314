"""Manoeuvres of the withheld-effect scenarios: random holds of speed and yaw-rate levels, with a pose."""

from __future__ import annotations

import numpy as np

from energy import CommandProfile
from terrawatt_base.checks import check_choice, check_real, check_seed

__all__ = ["MANOEUVRES", "manoeuvre_commands"]

_REST_S = 1.0
_RAMP_S = 0.3  # commands ramp over this time (s)

#: Manoeuvres by name: commanded speed levels (m/s), yaw-rate levels (rad/s) and hold range
#: (s); each run holds random combinations between a rest at each end.
MANOEUVRES: dict[str, tuple[tuple[float, ...], tuple[float, ...], tuple[float, float]]] = {
    "pivots_arcs": ((0.0, 0.0, 0.2, 0.4), (-1.0, -0.5, 0.5, 1.0), (1.5, 3.0)),
    "mixed": ((0.0, 0.2, 0.4, 0.6, 0.8), (-0.5, 0.0, 0.0, 0.5), (1.5, 3.0)),
    "start_stop": ((0.0, 0.0, 0.8, 1.0, -0.6), (0.0,), (0.8, 1.5)),
    "creep": ((0.0, 0.02, 0.05, 0.1), (0.0,), (1.5, 3.0)),
    "pivot_go": ((0.0,), (-1.0, 0.0, 1.0), (0.5, 1.0)),
    "speed_sweep": ((0.2, 0.5, 0.8, 1.0, 1.2), (0.0,), (2.0, 4.0)),
    "top_speed": ((1.0, 1.2, 1.4), (-0.3, 0.0, 0.3), (2.0, 4.0)),
    "tight_arcs": ((0.8, 1.0), (-1.8, -1.5, 1.5, 1.8), (1.5, 3.0)),
    "hills": ((0.0, 0.3, 0.5, 0.7), (-0.6, 0.0, 0.0, 0.6), (2.0, 4.0)),
}



def manoeuvre_commands(name: str, duration_s: float, *, seed: int | None = 0, dt_s: float = 0.01,
                       start_xy_m: tuple[float, float] = (0.0, 0.0)) -> CommandProfile:
    """Commands of the manoeuvre ``name``: random holds of its levels between rests, with the pose.

    Each hold lasts a random time in the manoeuvre's range; the commands ramp over 0.3 s
    (hard but finite accelerations: the model under test differentiates the logged speeds,
    and a step would make its central differences disagree with the truth's backward ones
    on the step's sample). The pose integrates the commands from ``start_xy_m`` at a random
    heading.

    Raises
    ------
    UnknownNameError
        ``name`` is not a key of :data:`MANOEUVRES`.
    InvalidParameterError
        A duration under 5 s, a bad step or seed.

    Examples
    --------
    >>> p = manoeuvre_commands("pivots_arcs", 10.0, seed=1)
    >>> len(p), p.pose_xyh is not None
    (1000, True)
    """
    check_choice("manoeuvre", name, MANOEUVRES)
    duration = check_real("duration_s", duration_s, low=5.0)
    dt = check_real("dt_s", dt_s, low=1e-4, high=0.1)
    rng = np.random.default_rng(check_seed(seed))
    levels_v, levels_w, (h_lo, h_hi) = MANOEUVRES[name]
    n = int(round(duration / dt))
    n_rest = int(round(_REST_S / dt))
    n_active = n - 2 * n_rest
    n_holds = n_active // max(1, int(round(h_lo / dt))) + 1
    holds = np.maximum(1, np.round(rng.uniform(h_lo, h_hi, n_holds) / dt).astype(np.int64))
    which = np.repeat(np.arange(n_holds), holds)[:n_active]
    v = np.zeros(n)
    w = np.zeros(n)
    v[n_rest:n_rest + n_active] = rng.choice(np.asarray(levels_v), n_holds)[which]
    w[n_rest:n_rest + n_active] = rng.choice(np.asarray(levels_w), n_holds)[which]
    k = max(1, int(round(_RAMP_S / dt)))
    box = np.ones(k) / k
    v = np.convolve(np.pad(v, (k, k), mode="edge"), box, mode="same")[k:-k]
    w = np.convolve(np.pad(w, (k, k), mode="edge"), box, mode="same")[k:-k]
    heading = rng.uniform(-np.pi, np.pi) + np.concatenate(([0.0], np.cumsum(w[:-1]) * dt))
    x = float(start_xy_m[0]) + np.concatenate(([0.0], np.cumsum(v[:-1] * np.cos(heading[:-1])) * dt))
    y = float(start_xy_m[1]) + np.concatenate(([0.0], np.cumsum(v[:-1] * np.sin(heading[:-1])) * dt))
    pose = np.column_stack([x, y, np.angle(np.exp(1j * heading))])
    return CommandProfile(np.arange(n) * dt, v, w, pose)
