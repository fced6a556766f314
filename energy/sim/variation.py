"""Ground variation: a smooth random field along the path that scales a ground's resistance."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from terrawatt_base.checks import check_real

from ..ground import GroundParams

__all__ = ["GroundVariation", "FACTOR_LOG_STEP", "variation_factor", "varied_ground_table"]

#: Resolution of the quantised resistance factor of ground variation (in log units: 0.5 %).
FACTOR_LOG_STEP = 0.005


@dataclass(frozen=True, kw_only=True)
class GroundVariation:
    """Slow, random variation of one ground's resistance along the path.

    A stationary Gaussian field ``z`` (unit variance, Gaussian smoothing of standard
    deviation ``length_scale_m`` over the distance travelled by the wheels) gives the
    factor ``exp(relative_std * z - relative_std**2 / 2)`` (mean 1), which multiplies the
    ground's rolling resistance, viscous and lateral friction coefficients (quantised to
    0.5 % steps), and raised to ``vibration_coupling`` its broadband roughness.

    Parameters
    ----------
    relative_std : float
        Log-normal spread of the factor (>= 0; 0.1 is about +/-10 %), at most 2.
    length_scale_m : float
        Correlation length (> 0), m of wheel travel.
    vibration_coupling : float
        Exponent (>= 0) of the factor on the roughness amplitude (0 = vibration unaffected).

    Raises
    ------
    InvalidParameterError
        Negative or non-finite values.
    """

    relative_std: float
    length_scale_m: float = 2.0
    vibration_coupling: float = 1.0

    def __post_init__(self) -> None:
        own = "GroundVariation"
        check_real("relative_std", self.relative_std, low=0.0, high=2.0, owner=own)
        check_real("length_scale_m", self.length_scale_m, low=0.0, low_inclusive=False, owner=own)
        check_real("vibration_coupling", self.vibration_coupling, low=0.0, owner=own)


def variation_factor(
    ground_index: np.ndarray,
    travel_m: np.ndarray,
    variations: Sequence[GroundVariation | None],
    seed: np.random.SeedSequence,
) -> np.ndarray:
    """Resistance factor per sample (1 for grounds without variation).

    ``ground_index`` indexes ``variations`` (one entry per ground, ``None`` = uniform);
    ``travel_m`` is the wheels' cumulative travel (non-decreasing). One child stream of
    ``seed`` is spawned per ground, in order.
    """
    factor = np.ones(ground_index.size)
    children = seed.spawn(len(variations))
    for k, var in enumerate(variations):
        mask = ground_index == k
        if var is None or var.relative_std == 0 or not mask.any():
            continue
        sigma_cells = 8.0  # grid step = length scale / 8
        step = var.length_scale_m / sigma_cells
        n_grid = int(travel_m[-1] / step) + 2
        pad = int(4 * sigma_cells) + 1  # the filter's reach (truncate=4)
        white = np.random.default_rng(children[k]).standard_normal(n_grid + 2 * pad)
        smooth = ndimage.gaussian_filter1d(white, sigma_cells)[pad : pad + n_grid]
        # unit variance: a normalised Gaussian kernel keeps 1 / (2 sqrt(pi) sigma) of it
        smooth /= math.sqrt(1.0 / (2.0 * math.sqrt(math.pi) * sigma_cells))
        z = np.interp(travel_m[mask], np.arange(n_grid) * step, smooth)
        factor[mask] = np.exp(var.relative_std * z - var.relative_std**2 / 2.0)
    return factor


def varied_ground_table(
    grounds: Sequence[GroundParams], ground_index: np.ndarray, factor: np.ndarray
) -> tuple[list[GroundParams], np.ndarray, np.ndarray]:
    """Grounds with their resistance scaled by the factor, quantised to :data:`FACTOR_LOG_STEP`.

    Returns the table of distinct (ground, factor level) grounds, the per-sample index into
    it and the quantised factor per sample.
    """
    level = np.round(np.log(factor) / FACTOR_LOG_STEP).astype(np.int64)
    pairs, inverse = np.unique(np.column_stack([ground_index, level]), axis=0, return_inverse=True)
    table = []
    for g, lv in pairs.tolist():
        base = grounds[g]
        f = math.exp(lv * FACTOR_LOG_STEP)
        if lv == 0:
            table.append(base)
            continue
        table.append(base.replace(
            rolling_resistance_coef=base.rolling_resistance_coef * f,
            viscous_friction_coef_s_per_m=base.viscous_friction_coef_s_per_m * f,
            lateral_friction_coef=base.effective_lateral_friction_coef * f,
        ))
    quantised = np.exp(level * FACTOR_LOG_STEP)
    return table, inverse.reshape(-1).astype(np.intp), quantised
