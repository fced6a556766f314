"""Ground parameter sets (frozen, validated): the wheel-ground contact of one ground class.

:class:`GroundParams` holds sliding friction (static, Coulomb, Stribeck), rolling and
viscous resistance, lateral friction for skid-steer turning and slip coefficients. How
each coefficient enters the model is documented in :mod:`energy.drivetrain`; presets are
in :mod:`energy.params`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from terrawatt_base.checks import check_real, check_text
from terrawatt_base.errors import InvalidParameterError

__all__ = ["GroundParams"]


@dataclass(frozen=True, kw_only=True)
class GroundParams:
    """Wheel-ground contact coefficients of one ground class.

    Parameters
    ----------
    name : str
        Ground class name (e.g. ``"asphalt"``).
    static_friction_coef : float
        mu_s: peak (static) sliding friction coefficient, >= ``coulomb_friction_coef``.
    coulomb_friction_coef : float
        mu_k (> 0): kinetic sliding friction coefficient; the traction limit of slip.
    stribeck_velocity_coef_s_per_m : float
        c_s (>= 0): decay rate of the static excess, ``exp(-c_s * |v|)``.
    viscous_friction_coef_s_per_m : float
        c_v (>= 0): viscous resistance per newton of normal load per m/s
        (force ``c_v * N * |v|``).
    rolling_resistance_coef : float
        Crr (>= 0): speed-independent rolling resistance per newton of normal load; the
        Coulomb level of the longitudinal resistance of a rolling wheel.
    lateral_friction_coef : float or None
        mu_lat (>= 0) of sideways sliding in skid-steer turns; ``None`` (default) takes
        ``coulomb_friction_coef``.
    longitudinal_slip_coef : float
        i0 (>= 0): slip-traction curve ``F / (mu_k N) = 1 - exp(-i / i0)``
        (Janosi-Hanamoto with ``i0 = K / L``, shear modulus over contact length).
    lateral_slip_coef : float
        k_y (>= 0): slip-angle tangent per unit of lateral force ratio,
        ``tan(alpha) = k_y * F_y / (mu_k N)``.

    Raises
    ------
    InvalidParameterError
        Non-finite or negative coefficients, ``static < coulomb``, empty name.
    """

    name: str
    static_friction_coef: float
    coulomb_friction_coef: float
    stribeck_velocity_coef_s_per_m: float = 0.0
    viscous_friction_coef_s_per_m: float = 0.0
    rolling_resistance_coef: float
    lateral_friction_coef: float | None = None
    longitudinal_slip_coef: float = 0.0
    lateral_slip_coef: float = 0.0

    def __post_init__(self) -> None:
        own = "GroundParams"
        check_text("name", self.name, owner=own)
        check_real("coulomb_friction_coef", self.coulomb_friction_coef, low=0.0,
                   low_inclusive=False, owner=own)
        check_real("static_friction_coef", self.static_friction_coef, low=0.0, owner=own)
        if self.static_friction_coef < self.coulomb_friction_coef:
            raise InvalidParameterError(
                f"GroundParams.static_friction_coef must be >= coulomb_friction_coef "
                f"({self.coulomb_friction_coef!r}), got {self.static_friction_coef!r}"
            )
        for name in ("stribeck_velocity_coef_s_per_m", "viscous_friction_coef_s_per_m",
                     "rolling_resistance_coef", "longitudinal_slip_coef", "lateral_slip_coef"):
            check_real(name, getattr(self, name), low=0.0, owner=own)
        if self.lateral_friction_coef is not None:
            check_real("lateral_friction_coef", self.lateral_friction_coef, low=0.0, owner=own)

    @property
    def effective_lateral_friction_coef(self) -> float:
        """``lateral_friction_coef``, or ``coulomb_friction_coef`` when it is ``None``."""
        if self.lateral_friction_coef is not None:
            return float(self.lateral_friction_coef)
        return float(self.coulomb_friction_coef)

    def replace(self, **changes: object) -> GroundParams:
        """Return a copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)
