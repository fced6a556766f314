"""Physics energy model of a two-sided (differential or skid-steer) DC-motor drive.

:class:`PhysicsEnergyModel` follows the physics paper (Turkish J. EECS 2022, "A novel
energy consumption model for autonomous mobile robot") and adds skid-steer turning
resistance, which that paper lacks. Every effect can be switched on or off by name
(:data:`EFFECTS`); everything is vectorised over arrays of samples. The model checks its
inputs and evaluates :func:`energy.drivetrain.drive_power`, whose module docstring gives
the equations and the documented deviations from the paper; its result is a
:class:`~energy.power.PowerBreakdown`. Planner-facing methods (energy per metre on a
grade, steepest feasible grade, segment and turn energies) price steady motion.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from terrawatt_base.checks import check_real, real_array
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from .drivetrain import EFFECTS, GroundArrays, drive_power
from .ground import GroundParams
from .power import PowerBreakdown, check_sample_times, trapezoid
from .robot import RobotParams

__all__ = ["EFFECTS", "PhysicsEnergyModel", "PowerBreakdown"]


def _samples(name: str, value: Any) -> np.ndarray:
    """Finite real samples (a scalar or an array): strings are refused, not parsed."""
    return real_array(name, value)


def _positive(name: str, value: Any) -> float:
    return check_real(name, value, low=0.0, low_inclusive=False)


class PhysicsEnergyModel:
    """Battery power and energy of a two-sided DC-motor drive, each effect switchable.

    See the module docstring for the equations and the documented deviations from the
    physics paper.

    Parameters
    ----------
    robot : RobotParams
        The vehicle.
    effects : iterable of str, optional
        Effects to include (names from :data:`EFFECTS`); ``None`` (default) includes all.
        Validated here, not in a ``fit`` (the model has nothing to learn yet); stored as a
        tuple in :data:`EFFECTS` order.

    Raises
    ------
    InvalidParameterError
        ``robot`` is not a RobotParams, or ``effects`` is a bare string.
    UnknownNameError
        An effect name is not in :data:`EFFECTS`.

    Examples
    --------
    >>> from energy import PhysicsEnergyModel, ground_preset, robot_preset
    >>> model = PhysicsEnergyModel(robot_preset("husky"))
    >>> e = model.energy_per_metre_j(0.5, [0.0, 0.1], ground_preset("asphalt"))
    >>> bool(e[1] > e[0] > 0)
    True
    """

    def __init__(self, robot: RobotParams, effects: Iterable[str] | None = None) -> None:
        if not isinstance(robot, RobotParams):
            raise InvalidParameterError(
                f"robot must be a RobotParams, got {type(robot).__name__!r}"
            )
        if effects is None:
            chosen = set(EFFECTS)
        else:
            if isinstance(effects, str):
                raise InvalidParameterError(
                    f"effects must be an iterable of effect names, not a string: {effects!r}"
                )
            chosen = set()
            for name in effects:
                if name not in EFFECTS:
                    raise UnknownNameError(
                        f"effect {name!r} is unknown; expected names from {EFFECTS!r}"
                    )
                chosen.add(name)
        self.robot = robot
        self.effects: tuple[str, ...] = tuple(e for e in EFFECTS if e in chosen)

    def __repr__(self) -> str:
        return f"PhysicsEnergyModel(robot={self.robot.name!r}, effects={self.effects!r})"

    def has(self, effect: str) -> bool:
        """Whether ``effect`` is switched on (raises UnknownNameError for unknown names)."""
        if effect not in EFFECTS:
            raise UnknownNameError(f"effect {effect!r} is unknown; expected names from {EFFECTS!r}")
        return effect in self.effects

    # ------------------------------------------------------------------ core
    def power(
        self,
        speed_mps: Any,
        omega_radps: Any,
        ground: GroundParams | Sequence[GroundParams],
        *,
        accel_mps2: Any = 0.0,
        alpha_radps2: Any = 0.0,
        slope_rad: Any = 0.0,
        time_s: Any = None,
        ground_index: Any = None,
    ) -> PowerBreakdown:
        """Power of each sample, with per-side motor current and per-effect components.

        All per-sample arguments broadcast to one 1-D shape ``(n,)``.

        Parameters
        ----------
        speed_mps : array_like
            Forward speed ``v`` (signed), m/s.
        omega_radps : array_like
            Yaw rate (positive counter-clockwise), rad/s.
        ground : GroundParams or sequence of GroundParams
            The ground of every sample, or a list indexed by ``ground_index``.
        accel_mps2 : array_like
            Forward acceleration ``dv/dt``, m/s^2 (default 0: steady).
        alpha_radps2 : array_like
            Yaw acceleration, rad/s^2 (default 0).
        slope_rad : array_like
            Pitch of the forward axis, positive nose-up (uphill when driving forward),
            in (-pi/2, pi/2).
        time_s : array_like, optional
            Strictly increasing sample times; only used for the control board's start-up
            interval (without it a moving robot's board is at its stable power).
        ground_index : array_like of int, optional
            Index into ``ground`` per sample (required when ``ground`` is a sequence).

        Returns
        -------
        PowerBreakdown

        Raises
        ------
        InvalidParameterError
            NaN/inf inputs, slopes outside (-pi/2, pi/2), shapes that do not broadcast to
            1-D, bad ground or ground_index.
        DataError
            ``time_s`` not strictly increasing.
        """
        v, omega, acc, alpha, slope = self._broadcast(
            speed_mps=speed_mps, omega_radps=omega_radps, accel_mps2=accel_mps2,
            alpha_radps2=alpha_radps2, slope_rad=slope_rad,
        )
        n = v.shape[0]
        gr = GroundArrays(ground, ground_index, n)
        t = None if time_s is None else check_sample_times(time_s, n)
        return drive_power(self.robot, self.effects, v, omega, acc, alpha, slope, gr, t)

    def holding_current_a(self, ground: GroundParams | Sequence[GroundParams], slope_rad: Any, *,
                          ground_index: Any = None) -> np.ndarray:
        """Per-side motor current (n, 2), A, that holds the robot standing still on ``slope_rad``.

        The physics at zero speed and acceleration on the slope: gravity's pull along it,
        ``m g sin(slope) / 2`` a side, held by the motors through the gear (the velocity
        controller of a robot without brakes holds it there), taken positive — a holding motor
        draws its current whichever way the slope pulls. Exact zeros where the slope is 0 and
        with the ``"slope"`` effect off.

        Parameters
        ----------
        ground : GroundParams or sequence of GroundParams
            As in :meth:`power`.
        slope_rad : array_like, shape (n,)
            Pitch under the robot, rad, in (-pi/2, pi/2).
        ground_index : array_like of int, optional
            As in :meth:`power`.

        Returns
        -------
        numpy.ndarray, shape (n, 2)

        Raises
        ------
        InvalidParameterError
            As in :meth:`power`.

        Examples
        --------
        >>> import numpy as np
        >>> from energy import PhysicsEnergyModel, robot_preset, ground_preset
        >>> hold = PhysicsEnergyModel(robot_preset("husky")).holding_current_a(ground_preset("asphalt"),
        ...                                                                    np.radians([0.0, 10.0]))
        >>> hold[0].tolist(), bool(hold[1, 0] > 2.0)
        ([0.0, 0.0], True)
        """
        slope = np.asarray(slope_rad, dtype=np.float64)
        if slope.ndim != 1:
            raise InvalidParameterError(f"slope_rad must be 1-D, got shape {slope.shape!r}")
        out = np.zeros((slope.shape[0], 2))
        on = slope != 0.0
        if "slope" in self.effects and on.any():
            still = np.zeros(int(on.sum()))
            res = self.power(still, still, ground, slope_rad=slope[on],
                             ground_index=None if ground_index is None else np.asarray(ground_index)[on])
            out[on] = np.abs(res.motor_current_a)
        return out

    def energy_j(
        self,
        time_s: Any,
        speed_mps: Any,
        omega_radps: Any,
        ground: GroundParams | Sequence[GroundParams],
        *,
        accel_mps2: Any = None,
        alpha_radps2: Any = None,
        slope_rad: Any = 0.0,
        ground_index: Any = None,
    ) -> float:
        """Battery energy (J) of a sampled motion, integrated with the trapezoid rule.

        Parameters
        ----------
        time_s : array_like, shape (n,)
            Strictly increasing sample times, s.
        speed_mps, omega_radps, slope_rad, ground, ground_index
            As in :meth:`power`.
        accel_mps2, alpha_radps2 : array_like, optional
            Accelerations; ``None`` (default) differentiates ``speed_mps`` /
            ``omega_radps`` over ``time_s`` (``numpy.gradient``).

        Returns
        -------
        float

        Raises
        ------
        InvalidParameterError, DataError
            As in :meth:`power`; also fewer than 2 samples.
        """
        t = np.asarray(time_s, dtype=np.float64)
        if t.ndim != 1 or t.shape[0] < 2:
            raise DataError(f"time_s must be 1-D with at least 2 samples, got shape {t.shape!r}")
        t = check_sample_times(t, t.shape[0])
        n = t.shape[0]
        v, w = _samples("speed_mps", speed_mps), _samples("omega_radps", omega_radps)
        if v.size not in (1, n) or w.size not in (1, n) or v.ndim > 1 or w.ndim > 1:
            raise InvalidParameterError(
                f"speed_mps and omega_radps must be scalars or have {n} samples like time_s, "
                f"got shapes {v.shape!r} and {w.shape!r}"
            )
        v = np.broadcast_to(v, (n,)).astype(np.float64)
        w = np.broadcast_to(w, (n,)).astype(np.float64)
        acc = np.gradient(v, t) if accel_mps2 is None else accel_mps2
        alpha = np.gradient(w, t) if alpha_radps2 is None else alpha_radps2
        res = self.power(v, w, ground, accel_mps2=acc, alpha_radps2=alpha,
                         slope_rad=slope_rad, time_s=t, ground_index=ground_index)
        return float(trapezoid(res.total_power_w, t))

    # --------------------------------------------------------------- planner
    def energy_per_metre_j(self, speed_mps: float, grade: Any, ground: GroundParams,
                           *, infeasible: str = "inf") -> np.ndarray:
        """Energy per metre (J/m) of steady straight driving on constant grades.

        Includes the electronics (sensor and stable control power divided by the speed)
        when those effects are on. Battery-side, so >= 0 for every grade when
        ``regen_efficiency`` is 0.

        A grade is *infeasible* at ``speed_mps`` when the drive cannot hold that speed on
        it: a side saturates (torque, power or speed limit, with the saturation effects on)
        or demands more than the traction limit (with a slip effect on) — uphill beyond the
        climbing limit, or downhill beyond what the motors can hold back (see
        :meth:`max_feasible_grade`). Planners need such grades to be impassable, not
        cheap, so by default they cost ``+inf`` (:class:`planner.EnergyCost` then refuses
        them in that direction only).

        Parameters
        ----------
        speed_mps : float
            Driving speed, m/s: > 0 and at most ``robot.max_speed_mps``.
        grade : array_like
            ``tan(beta) = dz/dl`` along the direction of motion, positive uphill.
        ground : GroundParams
        infeasible : {"inf", "capped"}
            ``"inf"`` (default) for infeasible grades; ``"capped"`` returns the saturated
            (capped) power instead — what the model says is drawn while the robot, driven
            there anyway, falls short of the commanded speed.

        Returns
        -------
        numpy.ndarray
            Same shape as ``grade``.

        Raises
        ------
        InvalidParameterError
            Non-positive or non-finite speed, a speed above ``robot.max_speed_mps``, NaN
            grades, ``ground`` not a GroundParams, an unknown ``infeasible``.

        Examples
        --------
        >>> from energy import PhysicsEnergyModel, ground_preset, robot_preset
        >>> m = PhysicsEnergyModel(robot_preset("jackal"), effects=["slope"])
        >>> float(m.energy_per_metre_j(1.0, 0.0, ground_preset("asphalt")))
        0.0
        """
        speed = _positive("speed_mps", speed_mps)
        if speed > self.robot.max_speed_mps:
            raise InvalidParameterError(
                f"speed_mps {speed_mps!r} exceeds the robot's max_speed_mps "
                f"{self.robot.max_speed_mps!r} ({self.robot.name!r})"
            )
        if infeasible not in ("inf", "capped"):
            raise UnknownNameError(f"infeasible must be 'inf' or 'capped', got {infeasible!r}")
        g = _samples("grade", grade)
        self._single_ground(ground)
        flat = g.reshape(-1)
        if flat.size == 0:
            return np.zeros(g.shape)
        res = self.power(speed, 0.0, ground, slope_rad=np.arctan(flat))
        e = res.total_power_w / speed
        if infeasible == "inf":
            e = np.where(res.saturated | res.traction_exceeded, np.inf, e)
        return e.reshape(g.shape)

    def max_feasible_grade(self, speed_mps: float, ground: GroundParams,
                           resolution: float = 1e-3) -> float:
        """Steepest uphill grade (``tan(beta)``) drivable at a steady ``speed_mps``.

        A grade is feasible when no sample saturates (with the saturation effects on) and
        the traction limit is not exceeded (with a slip effect on); a planner's slope
        limit should not exceed it. Searched on a grid of step ``resolution`` up to 5.0.

        Returns
        -------
        float
            The largest feasible grade on the grid (0.0 if even flat ground is not).

        Raises
        ------
        InvalidParameterError
            Non-positive speed or resolution, ``ground`` not a GroundParams.
        """
        speed = _positive("speed_mps", speed_mps)
        step = _positive("resolution", resolution)
        self._single_ground(ground)
        grades = np.arange(0.0, 5.0 + step / 2, step)
        res = self.power(speed, 0.0, ground, slope_rad=np.arctan(grades))
        bad = res.saturated | res.traction_exceeded
        if not bad.any():
            return float(grades[-1])
        first = int(np.argmax(bad))
        return float(grades[first - 1]) if first > 0 else 0.0

    def segment_energy_j(self, length_m: Any, speed_mps: float, grade: Any,
                         ground: GroundParams) -> np.ndarray:
        """Energy (J) of straight segments: ``length_m * energy_per_metre_j``.

        ``length_m`` (>= 0) and ``grade`` broadcast together.

        Raises
        ------
        InvalidParameterError
            Negative or NaN lengths, plus the errors of :meth:`energy_per_metre_j`.
        """
        length = _samples("length_m", length_m)
        if np.any(length < 0):
            raise InvalidParameterError(
                f"length_m must be >= 0, got {np.atleast_1d(length[length < 0])[:3]!r}"
            )
        length, g = np.broadcast_arrays(length, _samples("grade", grade))
        return length * self.energy_per_metre_j(speed_mps, g, ground)

    def turn_energy_j(self, heading_change_rad: Any, ground: GroundParams,
                      grade: Any = 0.0) -> np.ndarray:
        """Energy (J) of turning in place by ``|heading_change_rad|``.

        The robot pivots at ``robot.turn_rate_radps`` (steady, no acceleration terms) for
        ``|heading_change_rad| / turn_rate_radps`` seconds; the energy includes the
        electronics over that time when those effects are on. ``grade`` is taken as the
        robot's pitch during the turn.

        Parameters
        ----------
        heading_change_rad : array_like
            Heading changes (sign ignored), rad.
        ground : GroundParams
        grade : array_like
            ``tan(pitch)``; broadcasts with ``heading_change_rad``.

        Returns
        -------
        numpy.ndarray
            ``>= 0``, zero for a zero heading change; broadcast shape.

        Raises
        ------
        InvalidParameterError
            NaN inputs, ``ground`` not a GroundParams.
        """
        dh = np.abs(_samples("heading_change_rad", heading_change_rad))
        g = _samples("grade", grade)
        self._single_ground(ground)
        dh, g = np.broadcast_arrays(dh, g)
        if dh.size == 0:
            return np.zeros(dh.shape)
        rate = self.robot.turn_rate_radps
        res = self.power(0.0, rate, ground, slope_rad=np.arctan(g.reshape(-1)))
        return (res.total_power_w.reshape(dh.shape) * dh / rate)

    # -------------------------------------------------------------- helpers
    @staticmethod
    def _single_ground(ground: Any) -> None:
        if not isinstance(ground, GroundParams):
            raise InvalidParameterError(
                f"ground must be a GroundParams, got {type(ground).__name__!r}"
            )

    @staticmethod
    def _broadcast(**arrays: Any) -> list[np.ndarray]:
        checked = {k: _samples(k, a) for k, a in arrays.items()}
        try:
            out = np.broadcast_arrays(*checked.values())
        except ValueError:
            shapes = {k: a.shape for k, a in checked.items()}
            raise InvalidParameterError(
                f"per-sample inputs must broadcast to one 1-D shape, got shapes {shapes!r}"
            ) from None
        if out[0].ndim > 1:
            raise InvalidParameterError(
                f"per-sample inputs must be scalars or 1-D arrays, got shape {out[0].shape!r}"
            )
        out = [np.atleast_1d(np.array(a, dtype=np.float64)) for a in out]
        slope = out[-1]
        if np.any(np.abs(slope) >= np.pi / 2):
            bad = slope[np.abs(slope) >= np.pi / 2][:3]
            raise InvalidParameterError(f"slope_rad must lie in (-pi/2, pi/2), got {bad!r}")
        return out
