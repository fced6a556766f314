"""The vibration-current paper's excitation pattern: stepped (v, omega) holds on one ground.

:func:`excitation_commands` builds the control pattern of the vibration-current paper (its
Fig. 5): stepped combinations of v in 0–0.4 m/s and omega in 0–1.05 rad/s, held a few
seconds each, every combination visited; used to collect interaction data on a ground
(issue 3's experiment, issue 4's excitation manoeuvre). Its result is a
:class:`~energy.commands.CommandProfile`; route profiles are in :mod:`energy.profiles`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from terrawatt_base.checks import check_choice, check_real, check_seed
from terrawatt_base.errors import InvalidParameterError

from .commands import CommandProfile

__all__ = [
    "excitation_commands",
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
    seed: int | None = 0,
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
    seed : int or None
        Seed of the order, hold times and signs (``None`` or an int in [0, 2**32);
        ``None`` draws fresh entropy).

    Returns
    -------
    CommandProfile
        ``round(duration_s / dt_s)`` samples starting at t = 0; no pose.

    Raises
    ------
    InvalidParameterError
        Non-positive duration or step, bad levels or hold range, a duration too short for
        the rests, a seed outside the seed rule.
    UnknownNameError
        ``omega_sign`` not in :data:`OMEGA_SIGNS`.

    Examples
    --------
    >>> p = excitation_commands(20.0, 0.01, seed=1)
    >>> len(p), float(p.v_mps.max()) <= 0.4, float(p.omega_radps.max()) <= 1.05
    (2000, True, True)
    """
    duration = check_real("duration_s", duration_s, low=0.0, low_inclusive=False)
    dt = check_real("dt_s", dt_s, low=0.0, low_inclusive=False)
    rest = check_real("rest_s", rest_s, low=0.0)
    speeds = _levels("speed_levels_mps", speed_levels_mps)
    omegas = _levels("omega_levels_radps", omega_levels_radps)
    try:
        h_lo, h_hi = (float(x) for x in hold_s)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"hold_s must be a pair (min_s, max_s), got {hold_s!r}") from None
    if not (math.isfinite(h_lo) and math.isfinite(h_hi) and 0 < h_lo <= h_hi):
        raise InvalidParameterError(f"hold_s must satisfy 0 < min <= max, got {hold_s!r}")
    check_choice("omega_sign", omega_sign, OMEGA_SIGNS)
    seed = check_seed(seed)
    n = int(round(duration / dt))
    n_rest = int(round(rest / dt))
    if n < 2 or n <= 2 * n_rest:
        raise InvalidParameterError(
            f"duration_s={duration_s!r} leaves no time for the pattern between two rests of rest_s={rest_s!r} "
            f"at dt_s={dt_s!r}"
        )
    rng = np.random.default_rng(seed)
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
