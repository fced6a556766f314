"""Operating regime of each drive sample: speed bin, turning, acceleration, grade, ground, map block.

Every label is computed from the log's own fields, vectorised over its samples; the bins and
thresholds are the module constants below. A dimension the log cannot inform (no pose, no
map, no ground label) is labelled :data:`UNKNOWN_LABEL` rather than guessed.

- **motion class** — a sample is *at rest* (standstill) by the library's one definition,
  :func:`energy.logs.rest_samples` (``|v|`` and ``|omega|`` below
  :data:`~energy.logs.REST_SPEED_MPS` and :data:`~energy.logs.REST_OMEGA_RADPS`, neither
  starting nor stopping): the samples where the current models predict their rest level.
  It *pivots* (turns on the spot, :func:`pivoting`) when ``|v| <``
  :data:`STANDSTILL_SPEED_MPS` (0.05 m/s) and ``|omega| >=`` :data:`TURN_RATE_RADPS`
  (0.1 rad/s). Otherwise it drives, if slowly (creeping, starting, stopping).
- **speed** — ``"standstill"`` (at rest), ``"pivot"`` (pivoting), ``"< 0.05 m/s"`` (slower
  than :data:`STANDSTILL_SPEED_MPS`, neither), then bins of ``|v_mps|`` with edges
  :data:`SPEED_EDGES_MPS`: ``"0.05-0.25 m/s"``, ``"0.25-0.5 m/s"``, ``"0.5-1 m/s"``,
  ``"> 1 m/s"``. A pivot draws the largest currents of a skid-steer robot, a standstill the
  smallest: they are never one slice.
- **turning** — ``"standstill"`` (at rest); ``"pivot"`` (pivoting); ``"arc"``: neither,
  ``|omega| >= TURN_RATE_RADPS`` and curvature ``|omega| / |v| >=``
  :data:`ARC_CURVATURE_PER_M`; ``"straight"``: the rest.
- **acceleration** — rate of change of the speed ``|v|`` after a centred moving average of
  :data:`ACCEL_SMOOTHING_S`: ``"accelerating"`` above :data:`ACCEL_THRESHOLD_MPS2`,
  ``"braking"`` below its negative, ``"steady"`` between.
- **grade** — the terrain's slope along the direction of motion (the pitch along the
  heading, sign flipped when reversing; the pitch is ``arctan(grad_x cos h + grad_y sin h)``
  from the map's bilinearly interpolated gradients, as the truth simulator computes it):
  ``"uphill"`` above :data:`LEVEL_GRADE_RAD` (2 degrees), ``"downhill"`` below its negative,
  ``"level"`` between; needs the log's poses and a ``terrain`` (an :class:`InteractionLog`
  carries no pitch of its own); samples off the map are unknown.
- **ground** — the log's per-sample ground labels, else its run-level ``meta.ground_label``.
- **space** — blocks of map cells about :data:`SPACE_BLOCK_M` metres wide
  (``"cells (10-14, 40-44)"``, rows then columns; ``"cell (12, 40)"`` for one-cell blocks);
  needs poses and a ``terrain``; samples off the map are ``"off map"``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from terrain.terrain_map import TerrainMap
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog, rest_samples

__all__ = [
    "UNKNOWN_LABEL",
    "OFF_MAP_LABEL",
    "REGIME_DIMENSIONS",
    "SPEED_EDGES_MPS",
    "SPEED_LABELS",
    "STANDSTILL_SPEED_MPS",
    "TURN_RATE_RADPS",
    "ARC_CURVATURE_PER_M",
    "TURNING_LABELS",
    "ACCEL_SMOOTHING_S",
    "ACCEL_THRESHOLD_MPS2",
    "ACCELERATION_LABELS",
    "LEVEL_GRADE_RAD",
    "GRADE_LABELS",
    "SPACE_BLOCK_M",
    "check_terrain",
    "pivoting",
    "speed_labels",
    "turning_labels",
    "acceleration_labels",
    "motion_grade_rad",
    "grade_labels",
    "ground_labels",
    "space_labels",
    "regime_labels",
]

#: Label of a sample whose regime the log (or the missing map) cannot tell.
UNKNOWN_LABEL = "unknown"
#: Space label of a sample whose pose lies outside the map.
OFF_MAP_LABEL = "off map"
#: Dimensions returned by :func:`regime_labels`, in order.
REGIME_DIMENSIONS = ("speed", "turning", "acceleration", "grade", "ground", "space")

#: Inner edges of the speed bins of ``|v|`` (m/s); below the first, a sample is at rest or pivots.
SPEED_EDGES_MPS = (0.05, 0.25, 0.5, 1.0)
#: Labels of the speed dimension, slowest first: at rest, pivoting, slower than the first
#: edge (neither), then the bins of ``|v|``.
SPEED_LABELS = ("standstill", "pivot", "< 0.05 m/s", "0.05-0.25 m/s", "0.25-0.5 m/s", "0.5-1 m/s", "> 1 m/s")
#: Below this ``|v|`` the robot hardly moves forward or back (m/s): with ``|omega|`` from
#: :data:`TURN_RATE_RADPS` on, it pivots.
STANDSTILL_SPEED_MPS = SPEED_EDGES_MPS[0]
#: From this ``|omega|`` on the robot is turning (rad/s).
TURN_RATE_RADPS = 0.1
#: From this curvature ``|omega| / |v|`` on a moving turn is an arc (1/m; radius <= 5 m).
ARC_CURVATURE_PER_M = 0.2
#: Turning labels.
TURNING_LABELS = ("standstill", "straight", "arc", "pivot")
#: Width of the centred moving average of the speed before differentiating (s).
ACCEL_SMOOTHING_S = 0.5
#: Speed change rate that counts as accelerating or braking (m/s^2).
ACCEL_THRESHOLD_MPS2 = 0.1
#: Acceleration labels.
ACCELERATION_LABELS = ("accelerating", "steady", "braking")
#: Grade along the motion within which the ground is level (rad; 2 degrees).
LEVEL_GRADE_RAD = math.radians(2.0)
#: Grade labels.
GRADE_LABELS = ("uphill", "level", "downhill")
#: Side of a space block (m); a block holds ``max(1, round(SPACE_BLOCK_M / cell_size_m))``
#: cells a side.
SPACE_BLOCK_M = 5.0


def check_terrain(terrain: Any) -> TerrainMap | None:
    """``terrain`` if it is ``None`` or a :class:`~terrain.TerrainMap`.

    Raises
    ------
    InvalidParameterError
        Anything else.
    """
    if terrain is not None and not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap or None, got {type(terrain).__name__!r}")
    return terrain


def _checked_log(log: Any) -> InteractionLog:
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {type(log).__name__!r}")
    if len(log) < 2:
        raise DataError(f"log has {len(log)} drive sample; regimes need at least 2 samples")
    return log


def _labelled(codes: np.ndarray, labels: tuple[str, ...]) -> np.ndarray:
    out = np.asarray(labels, dtype=object)[codes].astype(str)
    out.setflags(write=False)
    return out


def pivoting(v_mps: Any, omega_radps: Any) -> Any:
    """Whether the robot turns on the spot: ``|v| <`` :data:`STANDSTILL_SPEED_MPS` and ``|omega| >=`` :data:`TURN_RATE_RADPS`.

    Never at rest (:func:`energy.logs.at_rest` needs ``|omega|`` far below the turn rate).

    Parameters
    ----------
    v_mps : float or array_like
        Forward speed (m/s), either sign.
    omega_radps : float or array_like
        Yaw rate (rad/s), either sign; broadcast against ``v_mps``.

    Returns
    -------
    bool or numpy.ndarray of bool
        A bool for scalar inputs, else an array of the broadcast shape.

    Examples
    --------
    >>> pivoting(0.0, 0.5), pivoting(0.0, -0.1), pivoting(0.0, 0.0), pivoting(0.5, 0.5)
    (True, True, False, False)
    >>> pivoting([0.0, 0.2], 0.5).tolist()
    [True, False]
    """
    out = (np.abs(np.asarray(v_mps, dtype=np.float64)) < STANDSTILL_SPEED_MPS) & (
        np.abs(np.asarray(omega_radps, dtype=np.float64)) >= TURN_RATE_RADPS)
    return bool(out) if out.ndim == 0 else out


def _motion_codes(log: InteractionLog) -> np.ndarray:
    """0 at rest, 1 pivoting, 2 driving, per sample."""
    return np.where(rest_samples(log), 0, np.where(pivoting(log.v_mps, log.omega_radps), 1, 2))


def speed_labels(log: InteractionLog) -> np.ndarray:
    """Speed class of each sample: ``"standstill"``, ``"pivot"``, ``"< 0.05 m/s"`` or a bin of :data:`SPEED_EDGES_MPS`."""
    log = _checked_log(log)
    bins = np.digitize(np.abs(log.v_mps), SPEED_EDGES_MPS)  # 0: below the first edge
    motion = _motion_codes(log)
    codes = np.where(motion < 2, motion, bins + 2)
    return _labelled(codes, SPEED_LABELS)


def turning_labels(log: InteractionLog) -> np.ndarray:
    """``"standstill"``, ``"straight"``, ``"arc"`` or ``"pivot"`` per sample (see module notes)."""
    log = _checked_log(log)
    speed, rate = np.abs(log.v_mps), np.abs(log.omega_radps)
    arc = (rate >= TURN_RATE_RADPS) & (rate >= ARC_CURVATURE_PER_M * speed)
    motion = _motion_codes(log)
    codes = np.where(motion == 0, 0, np.where(motion == 1, 3, np.where(arc, 2, 1)))
    return _labelled(codes, TURNING_LABELS)


def _moving_average(t: np.ndarray, x: np.ndarray, width_s: float) -> np.ndarray:
    """Centred moving average of the piecewise-linear ``x`` over ``width_s`` (clipped at the ends)."""
    cum = np.concatenate(([0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * np.diff(t))))
    lo = np.maximum(t - 0.5 * width_s, t[0])
    hi = np.minimum(t + 0.5 * width_s, t[-1])
    span = hi - lo
    area = np.interp(hi, t, cum) - np.interp(lo, t, cum)
    return np.where(span > 0, area / np.where(span > 0, span, 1.0), x)


def acceleration_labels(log: InteractionLog) -> np.ndarray:
    """``"accelerating"``, ``"steady"`` or ``"braking"`` per sample (see module notes)."""
    log = _checked_log(log)
    speed = np.abs(_moving_average(log.time_s, log.v_mps, ACCEL_SMOOTHING_S))
    rate = np.gradient(speed, log.time_s)
    codes = np.where(rate > ACCEL_THRESHOLD_MPS2, 0, np.where(rate < -ACCEL_THRESHOLD_MPS2, 2, 1))
    return _labelled(codes, ACCELERATION_LABELS)


def motion_grade_rad(log: InteractionLog, terrain: TerrainMap | None) -> np.ndarray | None:
    """Grade along the direction of motion per sample (rad, positive uphill), NaN off the map.

    ``None`` when the log has no poses or no ``terrain`` is given.

    Raises
    ------
    InvalidParameterError
        ``terrain`` is not a TerrainMap.
    """
    log = _checked_log(log)
    terrain = check_terrain(terrain)
    if terrain is None or log.pose_xyh is None:
        return None
    x, y, h = log.pose_xyh[:, 0], log.pose_xyh[:, 1], log.pose_xyh[:, 2]
    inside = np.asarray(terrain.contains(x, y), dtype=bool)
    out = np.full(len(log), np.nan)
    if inside.any():
        xi, yi, hi = x[inside], y[inside], h[inside]
        gx = np.asarray(terrain.sample("grad_x", xi, yi, method="bilinear"), dtype=np.float64)
        gy = np.asarray(terrain.sample("grad_y", xi, yi, method="bilinear"), dtype=np.float64)
        pitch = np.arctan(gx * np.cos(hi) + gy * np.sin(hi))
        out[inside] = np.where(log.v_mps[inside] < 0, -pitch, pitch)
    return out


def grade_labels(log: InteractionLog, terrain: TerrainMap | None = None) -> np.ndarray:
    """``"uphill"``, ``"level"``, ``"downhill"`` or ``"unknown"`` per sample (see module notes)."""
    grade = motion_grade_rad(log, terrain)
    if grade is None:
        return _labelled(np.zeros(len(log), dtype=np.intp), (UNKNOWN_LABEL,))
    codes = np.where(grade > LEVEL_GRADE_RAD, 0, np.where(grade < -LEVEL_GRADE_RAD, 2, 1))
    codes = np.where(np.isnan(grade), 3, codes)
    return _labelled(codes, (*GRADE_LABELS, UNKNOWN_LABEL))


def ground_labels(log: InteractionLog) -> np.ndarray:
    """The log's ground label per sample (per-sample labels, else the run's label, else unknown)."""
    log = _checked_log(log)
    labels = log.ground_labels
    if labels is None:
        return _labelled(np.zeros(len(log), dtype=np.intp), (UNKNOWN_LABEL,))
    out = np.asarray(labels).astype(str)
    out.setflags(write=False)
    return out


def _block_name(row: int, col: int, block: int, shape: tuple[int, int]) -> str:
    if block == 1:
        return f"cell ({row}, {col})"
    last_row, last_col = min(row + block, shape[0]) - 1, min(col + block, shape[1]) - 1
    return f"cells ({row}-{last_row}, {col}-{last_col})"


def space_labels(log: InteractionLog, terrain: TerrainMap | None = None) -> np.ndarray:
    """Map block of each sample (see module notes); unknown without poses or map."""
    log = _checked_log(log)
    terrain = check_terrain(terrain)
    if terrain is None or log.pose_xyh is None:
        return _labelled(np.zeros(len(log), dtype=np.intp), (UNKNOWN_LABEL,))
    x, y = log.pose_xyh[:, 0], log.pose_xyh[:, 1]
    inside = np.asarray(terrain.contains(x, y), dtype=bool)
    codes = np.zeros(len(log), dtype=np.intp)  # 0: off the map, k > 0: the k-th block met
    names = [OFF_MAP_LABEL]
    if inside.any():
        rows, cols = terrain.rowcol(x[inside], y[inside])
        block = max(1, int(round(SPACE_BLOCK_M / terrain.cell_size_m)))
        r0, c0 = np.atleast_1d(rows) // block * block, np.atleast_1d(cols) // block * block
        keys, inv = np.unique(r0 * terrain.shape[1] + c0, return_inverse=True)
        codes[inside] = inv.reshape(-1) + 1
        names += [_block_name(int(k // terrain.shape[1]), int(k % terrain.shape[1]), block, terrain.shape) for k in keys]
    return _labelled(codes, tuple(names))


def regime_labels(log: InteractionLog, *, terrain: TerrainMap | None = None) -> dict[str, np.ndarray]:
    """Per-sample regime labels of a log, one array of str per dimension.

    Parameters
    ----------
    log : InteractionLog
        The run (at least 2 drive samples).
    terrain : TerrainMap, optional
        The map the run drove on; with the log's poses it gives the grade and the map
        blocks (without it those are ``"unknown"``).

    Returns
    -------
    dict of str to numpy.ndarray of str, shape (N,)
        Keys :data:`REGIME_DIMENSIONS`: ``"speed"``, ``"turning"``, ``"acceleration"``,
        ``"grade"``, ``"ground"``, ``"space"`` (read-only arrays; bins in the module notes).

    Raises
    ------
    InvalidParameterError
        ``log`` is not an InteractionLog; ``terrain`` is not a TerrainMap.
    DataError
        A log with fewer than 2 samples.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(4) * 0.1
    >>> log = InteractionLog(t, [0.0, 0.0, 0.6, 0.6], [0.5, 0.5, 0.0, 0.3], np.ones(4), np.ones(4),
    ...                      t, np.full(4, 9.81))
    >>> regime_labels(log)["turning"].tolist()
    ['pivot', 'pivot', 'straight', 'arc']
    """
    log = _checked_log(log)
    terrain = check_terrain(terrain)
    return {
        "speed": speed_labels(log),
        "turning": turning_labels(log),
        "acceleration": acceleration_labels(log),
        "grade": grade_labels(log, terrain),
        "ground": ground_labels(log),
        "space": space_labels(log, terrain),
    }

