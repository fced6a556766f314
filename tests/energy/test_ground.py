"""energy.ground: validation of GroundParams."""

from __future__ import annotations

import pytest

from energy import GroundParams
from terrain import InvalidParameterError


def test_ground_string_coefficient_names_the_parameter() -> None:
    with pytest.raises(InvalidParameterError, match="GroundParams.rolling_resistance_coef must be a real number"):
        GroundParams(name="g", static_friction_coef=0.5, coulomb_friction_coef=0.5,
                     rolling_resistance_coef="0.01")  # type: ignore[arg-type]


def test_ground_validation() -> None:
    with pytest.raises(InvalidParameterError, match="static_friction_coef must be >= coulomb"):
        GroundParams(name="g", static_friction_coef=0.3, coulomb_friction_coef=0.5,
                     rolling_resistance_coef=0.01)
    with pytest.raises(InvalidParameterError, match="rolling_resistance_coef must be >= 0"):
        GroundParams(name="g", static_friction_coef=0.5, coulomb_friction_coef=0.5,
                     rolling_resistance_coef=-0.01)
    with pytest.raises(InvalidParameterError, match="coulomb_friction_coef must be > 0"):
        GroundParams(name="g", static_friction_coef=0.5, coulomb_friction_coef=0.0,
                     rolling_resistance_coef=0.01)
