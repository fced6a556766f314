"""Velocity command profiles: the source paper's excitation pattern and waypoint routes.

A :class:`CommandProfile` is a uniformly sampled series of commanded linear speed and yaw
rate (optionally with the reference pose the commands follow). Two builders make them:

- :func:`excitation_commands` — the control pattern of the vibration-current paper (its
  Fig. 5): stepped combinations of v in 0–0.4 m/s and omega in 0–1.05 rad/s, held a few
  seconds each, every combination visited; used to collect interaction data on a ground
  (issue 3's experiment, issue 4's excitation manoeuvre).
- :func:`waypoint_commands` — a stop-turn-go velocity profile along a polyline route:
  at every waypoint the robot pivots in place to the next segment's heading, then drives
  the segment with a trapezoidal speed profile (acceleration limits), all evaluated
  in closed form, vectorised over the samples.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain.errors import DataError, InvalidParameterError, UnknownNameError

__all__ = [
    "CommandProfile",
    "excitation_commands",
    "waypoint_commands",
    "PAPER_SPEED_LEVELS_MPS",
    "PAPER_OMEGA_LEVELS_RADPS",
    "OMEGA_SIGNS",
]

#: Commanded speed levels of the paper's excitation pattern (m/s), 0–0.4 m/s.
PAPER_SPEED_LEVELS_MPS: tuple[float, ...] = (0.0, 0.1, 0.2, 0.3, 0.4)
#: Commanded yaw-rate levels of the paper's excitation pattern (rad/s), 0–1.05 rad/s.
PAPER_OMEGA_LEVELS_RADPS: tuple[float, ...] = (0.0, 0.35, 0.7, 1.05)
#: ``omega_sign`` values of :func:`excitation_commands`.
OMEGA_SIGNS = ("positive", "both")

# Relative tolerance on the uniformity of a profile's time steps.
_UNIFORM_RTOL = 1e-6


def _finite_number(name: str, value: Any, *, positive: bool = False, low: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(f"{name} must be a finite number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{name} must be a finite number, got {value!r}")
    if positive and v <= 0:
        raise InvalidParameterError(f"{name} must be > 0, got {value!r}")
    if low is not None and v < low:
        raise InvalidParameterError(f"{name} must be >= {low!r}, got {value!r}")
    return v


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class CommandProfile:
    """Commanded linear speed and yaw rate on a uniform time grid.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Uniformly spaced, strictly increasing sample times (s), N >= 2.
    v_mps : array_like, shape (N,)
        Commanded forward speed (m/s, signed).
    omega_radps : array_like, shape (N,)
        Commanded yaw rate (rad/s, counter-clockwise positive).
    pose_xyh : array_like, shape (N, 3), optional
        Reference pose (x_m, y_m, heading_rad) the commands follow, when known.

    Raises
    ------
    InvalidParameterError
        Wrong shapes or lengths, fewer than 2 samples.
    DataError
        Non-finite values; times not strictly increasing or not uniformly spaced.

    Examples
    --------
    >>> p = CommandProfile([0.0, 0.1, 0.2], [0.0, 0.2, 0.2], [0.0, 0.0, 0.5])
    >>> round(p.dt_s, 6), round(p.duration_s, 6)
    (0.1, 0.2)
    """

    time_s: np.ndarray
    v_mps: np.ndarray
    omega_radps: np.ndarray
    pose_xyh: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = _vector("time_s", self.time_s)
        if t.size < 2:
            raise InvalidParameterError(f"time_s must hold at least 2 samples, got {t.size}")
        _check_uniform_time("time_s", t)
        object.__setattr__(self, "time_s", _readonly(t))
        for name in ("v_mps", "omega_radps"):
            arr = _vector(name, getattr(self, name))
            if arr.size != t.size:
                raise InvalidParameterError(f"{name} must have the length of time_s ({t.size}), got {arr.size}")
            object.__setattr__(self, name, _readonly(arr))
        if self.pose_xyh is not None:
            try:
                pose = np.array(self.pose_xyh, dtype=np.float64)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"pose_xyh must be a numeric (N, 3) array, got {self.pose_xyh!r:.80}") from None
            if pose.shape != (t.size, 3):
                raise InvalidParameterError(f"pose_xyh must have shape ({t.size}, 3), got {pose.shape!r}")
            if not np.all(np.isfinite(pose)):
                raise DataError("pose_xyh must be finite (no NaN or inf)")
            object.__setattr__(self, "pose_xyh", _readonly(pose))

    def __len__(self) -> int:
        return int(self.time_s.size)

    @property
    def dt_s(self) -> float:
        """Sampling period (s)."""
        return float((self.time_s[-1] - self.time_s[0]) / (self.time_s.size - 1))

    @property
    def duration_s(self) -> float:
        """Last minus first sample time (s)."""
        return float(self.time_s[-1] - self.time_s[0])

    @classmethod
    def from_poses(cls, time_s: Any, pose_xyh: Any) -> CommandProfile:
        """Commands that reproduce a pose trajectory (differentiated, ``numpy.gradient``).

        ``v`` is the velocity projected on the heading (negative when reversing), ``omega``
        the derivative of the unwrapped heading.

        Parameters
        ----------
        time_s : array_like, shape (N,)
            Uniformly spaced times (s).
        pose_xyh : array_like, shape (N, 3)
            x_m, y_m, heading_rad.

        Returns
        -------
        CommandProfile
            With ``pose_xyh`` set.

        Raises
        ------
        InvalidParameterError, DataError
            As for the constructor.
        """
        t = _vector("time_s", time_s)
        if t.size < 2:
            raise InvalidParameterError(f"time_s must hold at least 2 samples, got {t.size}")
        _check_uniform_time("time_s", t)
        try:
            pose = np.array(pose_xyh, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"pose_xyh must be a numeric (N, 3) array, got {pose_xyh!r:.80}") from None
        if pose.shape != (t.size, 3):
            raise InvalidParameterError(f"pose_xyh must have shape ({t.size}, 3), got {pose.shape!r}")
        if not np.all(np.isfinite(pose)):
            raise DataError("pose_xyh must be finite (no NaN or inf)")
        heading = np.unwrap(pose[:, 2])
        vx = np.gradient(pose[:, 0], t)
        vy = np.gradient(pose[:, 1], t)
        v = vx * np.cos(heading) + vy * np.sin(heading)
        omega = np.gradient(heading, t)
        return cls(t, v, omega, pose)


def _vector(name: str, value: Any, n: int | None = None) -> np.ndarray:
    """A finite 1-D float64 copy of ``value`` (of length ``n`` when given)."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be an array of numbers, got {value!r:.80}") from None
    if arr.ndim != 1:
        raise InvalidParameterError(f"{name} must be 1-D, got shape {arr.shape!r}")
    if n is not None and arr.size != n:
        raise InvalidParameterError(f"{name} must have the length of time_s ({n}), got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"{name} must be finite; {int(bad.sum())} non-finite value(s), first at index {i} ({arr[i]!r})")
    return arr


def _check_uniform_time(name: str, t: np.ndarray) -> float:
    """Raise DataError unless ``t`` is strictly increasing with uniform steps; return the step."""
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0)) + 1
        raise DataError(f"{name} must be strictly increasing; t[{i}]={t[i]!r} follows t[{i - 1}]={t[i - 1]!r}")
    step = float((t[-1] - t[0]) / (t.size - 1))
    dev = np.abs(d - step)
    if np.any(dev > _UNIFORM_RTOL * step + 1e-12):
        i = int(np.argmax(dev)) + 1
        raise DataError(
            f"{name} must be uniformly spaced (step {step!r} s); the step before index {i} is {d[i - 1]!r} s "
            "— resample the commands onto a uniform grid first"
        )
    return step


def _levels(name: str, values: Sequence[float]) -> np.ndarray:
    try:
        arr = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a sequence of numbers, got {values!r}") from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise InvalidParameterError(f"{name} must be a non-empty sequence of finite numbers >= 0, got {values!r}")
    return arr


def excitation_commands(
    duration_s: float = 160.0,
    dt_s: float = 0.01,
    *,
    speed_levels_mps: Sequence[float] = PAPER_SPEED_LEVELS_MPS,
    omega_levels_radps: Sequence[float] = PAPER_OMEGA_LEVELS_RADPS,
    hold_s: tuple[float, float] = (3.0, 5.0),
    rest_s: float = 1.0,
    omega_sign: str = "positive",
    seed: int = 0,
) -> CommandProfile:
    """The paper's excitation pattern: stepped (v, omega) combinations held a few seconds.

    The profile starts and ends with ``rest_s`` seconds at rest. In between, the
    combinations of ``speed_levels_mps`` x ``omega_levels_radps`` are visited in a random
    order (a new permutation each cycle through all of them, so every combination appears
    about equally often), each held for a duration drawn uniformly from ``hold_s`` and
    rounded to whole samples; the last hold is cut at ``duration_s - rest_s``. Commands are
    steps (the robot's velocity lag smooths them, see ``TruthSimulator``).

    Parameters
    ----------
    duration_s : float
        Total length (s), > 2 * ``rest_s``; the paper's runs last about 160 s.
    dt_s : float
        Sampling period (s), > 0 (0.01 s = 100 Hz as in the paper).
    speed_levels_mps, omega_levels_radps : sequence of float
        Levels (>= 0) combined; default the paper's 0–0.4 m/s and 0–1.05 rad/s.
    hold_s : (float, float)
        Minimum and maximum hold time of one combination (s), 0 < min <= max.
    rest_s : float
        Rest at the start and end (s), >= 0.
    omega_sign : {"positive", "both"}
        ``"positive"``: counter-clockwise turns only (the paper's 0–1.05 rad/s);
        ``"both"``: each hold's yaw rate gets a random sign.
    seed : int
        Seed of the order, hold times and signs.

    Returns
    -------
    CommandProfile
        ``round(duration_s / dt_s)`` samples starting at t = 0; no pose.

    Raises
    ------
    InvalidParameterError
        Non-positive duration or step, bad levels or hold range, a duration too short for
        the rests, a non-integer seed.
    UnknownNameError
        ``omega_sign`` not in :data:`OMEGA_SIGNS`.

    Examples
    --------
    >>> p = excitation_commands(20.0, 0.01, seed=1)
    >>> len(p), float(p.v_mps.max()) <= 0.4, float(p.omega_radps.max()) <= 1.05
    (2000, True, True)
    """
    duration = _finite_number("duration_s", duration_s, positive=True)
    dt = _finite_number("dt_s", dt_s, positive=True)
    rest = _finite_number("rest_s", rest_s, low=0.0)
    speeds = _levels("speed_levels_mps", speed_levels_mps)
    omegas = _levels("omega_levels_radps", omega_levels_radps)
    try:
        h_lo, h_hi = (float(x) for x in hold_s)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"hold_s must be a pair (min_s, max_s), got {hold_s!r}") from None
    if not (math.isfinite(h_lo) and math.isfinite(h_hi) and 0 < h_lo <= h_hi):
        raise InvalidParameterError(f"hold_s must satisfy 0 < min <= max, got {hold_s!r}")
    if omega_sign not in OMEGA_SIGNS:
        raise UnknownNameError(f"omega_sign must be one of {OMEGA_SIGNS!r}, got {omega_sign!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise InvalidParameterError(f"seed must be an int, got {seed!r}")
    n = int(round(duration / dt))
    n_rest = int(round(rest / dt))
    if n < 2 or n <= 2 * n_rest:
        raise InvalidParameterError(
            f"duration_s={duration_s!r} leaves no time for the pattern between two rests of rest_s={rest_s!r} "
            f"at dt_s={dt_s!r}"
        )
    rng = np.random.default_rng(int(seed))
    combos = np.array([(v, w) for v in speeds for w in omegas], dtype=np.float64)
    n_active = n - 2 * n_rest
    min_hold = max(1, int(round(h_lo / dt)))
    # enough holds to fill the active span, drawn in one go
    n_holds = n_active // min_hold + 1
    n_cycles = -(-n_holds // len(combos))
    order = np.concatenate([rng.permutation(len(combos)) for _ in range(n_cycles)])[:n_holds]
    holds = np.maximum(1, np.round(rng.uniform(h_lo, h_hi, n_holds) / dt).astype(np.int64))
    signs = rng.choice([-1.0, 1.0], n_holds) if omega_sign == "both" else np.ones(n_holds)
    which = np.repeat(np.arange(n_holds), holds)[:n_active]
    v = np.zeros(n)
    w = np.zeros(n)
    v[n_rest : n_rest + n_active] = combos[order[which], 0]
    w[n_rest : n_rest + n_active] = combos[order[which], 1] * signs[which]
    return CommandProfile(np.arange(n, dtype=np.float64) * dt, v, w)


# --------------------------------------------------------------------- waypoint routes
def _trapezoid_times(distance: np.ndarray, v_max: float, a_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Peak speed, acceleration time and total time of rest-to-rest trapezoid moves."""
    full = distance >= v_max**2 / a_max
    peak = np.where(full, v_max, np.sqrt(distance * a_max))
    t_acc = peak / a_max
    with np.errstate(invalid="ignore", divide="ignore"):
        t_cruise = np.where(full, (distance - v_max**2 / a_max) / v_max, 0.0)
    return peak, t_acc, 2.0 * t_acc + t_cruise


def _trapezoid_eval(tau: np.ndarray, distance: np.ndarray, peak: np.ndarray, t_acc: np.ndarray,
                    total: np.ndarray, a_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and speed of a trapezoid move ``tau`` seconds after its start (clamped)."""
    tau = np.clip(tau, 0.0, total)
    t_dec = total - t_acc
    acc_phase = tau < t_acc
    dec_phase = tau > t_dec
    s_cruise = 0.5 * a_max * t_acc**2 + peak * (tau - t_acc)
    rem = total - tau
    s = np.where(acc_phase, 0.5 * a_max * tau**2, np.where(dec_phase, distance - 0.5 * a_max * rem**2, s_cruise))
    v = np.where(acc_phase, a_max * tau, np.where(dec_phase, a_max * rem, peak))
    return s, v


def waypoint_commands(
    waypoints_xy_m: Any,
    speed_mps: float,
    *,
    accel_mps2: float = 0.5,
    turn_rate_radps: float = 0.5,
    yaw_accel_radps2: float = 1.0,
    dt_s: float = 0.01,
    start_heading_rad: float | None = None,
) -> CommandProfile:
    """Stop-turn-go commands along a polyline, with the reference pose.

    At each waypoint the robot turns in place to the next segment's heading (the shorter
    way round) with a trapezoidal yaw-rate profile (``turn_rate_radps``,
    ``yaw_accel_radps2``), then drives the segment from rest to rest with a trapezoidal
    speed profile (``speed_mps``, ``accel_mps2``); segments too short to reach the
    cruise speed get a triangular profile. The first turn happens only when
    ``start_heading_rad`` is given. Positions and headings follow in closed form.

    Parameters
    ----------
    waypoints_xy_m : array_like, shape (K, 2)
        Route vertices (m), K >= 2, no two consecutive ones equal.
    speed_mps : float
        Cruise speed (m/s), > 0.
    accel_mps2, turn_rate_radps, yaw_accel_radps2 : float
        Acceleration limit (m/s^2), pivot yaw rate (rad/s) and yaw-acceleration limit
        (rad/s^2), all > 0.
    dt_s : float
        Sampling period (s), > 0.
    start_heading_rad : float, optional
        Heading at the start; ``None`` starts facing the first segment.

    Returns
    -------
    CommandProfile
        Samples ``k * dt_s`` up to the first one at or after the end of the route (which
        is at rest at the last waypoint), with ``pose_xyh`` (heading wrapped to (-pi, pi]).

    Raises
    ------
    InvalidParameterError
        Bad shapes, non-finite or repeated waypoints, non-positive limits.

    Examples
    --------
    >>> p = waypoint_commands([[0.0, 0.0], [2.0, 0.0]], 0.5, dt_s=0.05)
    >>> round(float(p.pose_xyh[-1, 0]), 6), float(p.v_mps[-1])
    (2.0, 0.0)
    """
    try:
        wp = np.array(waypoints_xy_m, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"waypoints_xy_m must be a numeric (K, 2) array, got {waypoints_xy_m!r:.80}") from None
    if wp.ndim != 2 or wp.shape[1] != 2 or wp.shape[0] < 2:
        raise InvalidParameterError(f"waypoints_xy_m must have shape (K, 2) with K >= 2, got {wp.shape!r}")
    if not np.all(np.isfinite(wp)):
        raise InvalidParameterError("waypoints_xy_m must be finite (no NaN or inf)")
    v_max = _finite_number("speed_mps", speed_mps, positive=True)
    a_max = _finite_number("accel_mps2", accel_mps2, positive=True)
    w_max = _finite_number("turn_rate_radps", turn_rate_radps, positive=True)
    al_max = _finite_number("yaw_accel_radps2", yaw_accel_radps2, positive=True)
    dt = _finite_number("dt_s", dt_s, positive=True)
    delta = np.diff(wp, axis=0)
    length = np.hypot(delta[:, 0], delta[:, 1])
    if np.any(length == 0):
        i = int(np.argmax(length == 0))
        raise InvalidParameterError(
            f"waypoints_xy_m[{i}] and waypoints_xy_m[{i + 1}] are equal ({wp[i].tolist()!r}); "
            "remove repeated waypoints"
        )
    heading = np.arctan2(delta[:, 1], delta[:, 0])
    if start_heading_rad is None:
        h_start = heading[0]
    else:
        h_start = _finite_number("start_heading_rad", start_heading_rad)
    prev = np.concatenate(([h_start], heading[:-1]))
    turn = np.angle(np.exp(1j * (heading - prev)))  # wrapped to (-pi, pi]
    k = heading.size
    # phases alternate: turn_0, straight_0, turn_1, straight_1, ...
    dist = np.empty(2 * k)
    dist[0::2] = np.abs(turn)
    dist[1::2] = length
    is_turn = np.zeros(2 * k, dtype=bool)
    is_turn[0::2] = True
    peak = np.empty(2 * k)
    t_acc = np.empty(2 * k)
    total = np.empty(2 * k)
    for mask, vm, am in ((is_turn, w_max, al_max), (~is_turn, v_max, a_max)):
        p, ta, tt = _trapezoid_times(dist[mask], vm, am)
        peak[mask], t_acc[mask], total[mask] = p, ta, tt
    starts = np.concatenate(([0.0], np.cumsum(total)))
    t_end = float(starts[-1])
    n = int(math.ceil(t_end / dt - 1e-9)) + 1
    t = np.arange(n, dtype=np.float64) * dt
    phase = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, 2 * k - 1)
    tau = t - starts[phase]
    a_phase = np.where(is_turn[phase], al_max, a_max)
    s, rate = _trapezoid_eval(tau, dist[phase], peak[phase], t_acc[phase], total[phase], a_phase)
    seg = phase // 2
    turning = is_turn[phase]
    sign = np.sign(turn[seg])
    v = np.where(turning, 0.0, rate)
    omega = np.where(turning, sign * rate, 0.0)
    unit = delta / length[:, None]
    xy = np.where(turning[:, None], wp[seg], wp[seg] + s[:, None] * unit[seg])
    h = np.where(turning, prev[seg] + sign * s, heading[seg])
    h = np.pi - np.mod(np.pi - h, 2.0 * np.pi)
    return CommandProfile(t, v, omega, np.column_stack([xy, h]))
