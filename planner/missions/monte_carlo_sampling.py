"""What a Monte Carlo mission varies: the ranges of its parameters (MissionDistributions) and one draw (MissionSample)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from energy import Battery, GroundParams, RobotParams
from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

__all__ = ["MissionDistributions", "MissionSample"]


def _range(name: str, value: Any, *, low: float, high: float | None = None, positive: bool = False) -> tuple[float, float]:
    """A checked ``(low, high)`` pair inside ``[low, high]`` (``low < ...`` with ``positive``), low <= high."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"MissionDistributions.{name} must be a (low, high) pair of numbers, got {value!r}"
        ) from None
    bounds = {"low": low, "high": high, "low_inclusive": not positive, "owner": "MissionDistributions"}
    lo = check_real(f"{name}[0]", lo, **bounds)
    hi = check_real(f"{name}[1]", hi, **bounds)
    if hi < lo:
        raise InvalidParameterError(f"MissionDistributions.{name} must have low <= high, got {value!r}")
    return lo, hi


@dataclass(frozen=True)
class MissionDistributions:
    """Ranges of the parameters a Monte Carlo mission draws, each uniform over ``(low, high)``.

    A range whose two ends are equal fixes that parameter.

    Parameters
    ----------
    ground_coef_scale : (float, float)
        Factor on each ground's friction and rolling-resistance coefficients (> 0), drawn
        independently per ground class. Default (0.8, 1.2).
    payload_kg : (float, float)
        Payload added to the robot's mass (kg, >= 0). Default (0, 20).
    capacity_fade_pct : (float, float)
        Loss of the battery's rated capacity (%, in [0, 100)). Default (0, 20).
    internal_resistance_ohm : (float, float)
        Internal resistance of the pack (ohm, >= 0), replacing the battery's. Default (0, 0.1).
    speed_scale : (float, float)
        Factor on the nominal driving speed (> 0). Default (0.9, 1.1).

    Raises
    ------
    InvalidParameterError
        A range that is not a pair of finite numbers in its bounds with low <= high.

    Examples
    --------
    >>> d = MissionDistributions(payload_kg=(10.0, 10.0))  # a fixed 10 kg payload
    >>> s = d.draw(np.random.default_rng(0), ["asphalt"], nominal_speed_mps=1.0)
    >>> s.payload_kg, 0.9 <= s.speed_mps <= 1.1
    (10.0, True)
    """

    ground_coef_scale: tuple[float, float] = (0.8, 1.2)
    payload_kg: tuple[float, float] = (0.0, 20.0)
    capacity_fade_pct: tuple[float, float] = (0.0, 20.0)
    internal_resistance_ohm: tuple[float, float] = (0.0, 0.1)
    speed_scale: tuple[float, float] = (0.9, 1.1)

    def __post_init__(self) -> None:
        checked = {
            "ground_coef_scale": _range("ground_coef_scale", self.ground_coef_scale, low=0.0, positive=True),
            "payload_kg": _range("payload_kg", self.payload_kg, low=0.0),
            "capacity_fade_pct": _range("capacity_fade_pct", self.capacity_fade_pct, low=0.0, high=99.0),
            "internal_resistance_ohm": _range("internal_resistance_ohm", self.internal_resistance_ohm, low=0.0),
            "speed_scale": _range("speed_scale", self.speed_scale, low=0.0, positive=True),
        }
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    def draw(self, rng: np.random.Generator, ground_names: Sequence[str], *, nominal_speed_mps: float) -> MissionSample:
        """One draw: the ground factors (one per name, in order), then payload, fade, resistance and speed."""
        if not isinstance(rng, np.random.Generator):
            raise InvalidParameterError(f"rng must be a numpy.random.Generator, got {type(rng).__name__!r}")
        speed = check_real("nominal_speed_mps", nominal_speed_mps, low=0.0, low_inclusive=False)
        scales = rng.uniform(*self.ground_coef_scale, size=len(ground_names))
        payload, fade, resistance, speed_scale = (
            rng.uniform(*r) for r in (self.payload_kg, self.capacity_fade_pct, self.internal_resistance_ohm,
                                      self.speed_scale)
        )
        return MissionSample(
            ground_scale=dict(zip(ground_names, (float(s) for s in scales))),
            payload_kg=float(payload), capacity_fade_pct=float(fade), internal_resistance_ohm=float(resistance),
            speed_mps=float(speed * speed_scale),
        )

    def to_dict(self) -> dict[str, list[float]]:
        """The ranges as plain lists (units in the keys)."""
        return {name: list(getattr(self, name)) for name in
                ("ground_coef_scale", "payload_kg", "capacity_fade_pct", "internal_resistance_ohm", "speed_scale")}


@dataclass(frozen=True)
class MissionSample:
    """The drawn parameters of one Monte Carlo mission.

    Attributes
    ----------
    ground_scale : dict of str to float
        Factor on each ground's friction and rolling-resistance coefficients.
    payload_kg, capacity_fade_pct, internal_resistance_ohm, speed_mps : float
        Payload, capacity loss, internal resistance and driving speed of this mission.
    """

    ground_scale: Mapping[str, float]
    payload_kg: float
    capacity_fade_pct: float
    internal_resistance_ohm: float
    speed_mps: float

    def robot(self, robot: RobotParams) -> RobotParams:
        """``robot`` carrying the payload."""
        return robot.replace(mass_kg=robot.mass_kg + self.payload_kg)

    def grounds(self, grounds: Mapping[str, GroundParams]) -> dict[str, GroundParams]:
        """Each ground with its friction and rolling-resistance coefficients scaled (grounds without a factor as given)."""
        out = {}
        for name, g in grounds.items():
            f = self.ground_scale.get(name, 1.0)
            lateral = None if g.lateral_friction_coef is None else g.lateral_friction_coef * f
            out[name] = g.replace(
                static_friction_coef=g.static_friction_coef * f, coulomb_friction_coef=g.coulomb_friction_coef * f,
                rolling_resistance_coef=g.rolling_resistance_coef * f, lateral_friction_coef=lateral,
            )
        return out

    def battery(self, battery: Battery) -> Battery:
        """``battery`` with the faded capacity and this internal resistance."""
        return battery.replace(capacity_ah=battery.capacity_ah * (1.0 - self.capacity_fade_pct / 100.0),
                               internal_resistance_ohm=self.internal_resistance_ohm)
