"""Withheld-effect scenarios: truth-simulator logs that excite one effect and a model that lacks it.

A :class:`Scenario` drives a Husky (100 Hz, a few runs of tens of seconds, realistic
:class:`~energy.NoiseModel` noise) through manoeuvres that excite one catalogued effect
(pivots and arcs for turning resistance, hard starts and stops for inertia, creeping for
Stribeck, pivots of a weak-motored robot for torque saturation, ...), with
:class:`~energy.TruthSimulator` and every physics effect on (the truth), and builds the
model under test: a :class:`~energy.PhysicsCurrentModel` with the withheld physics
effects switched off, calibrated (its idle current) on a standstill log. For parameter
errors the truth's robot or ground differs from the model's; for measurement effects
(per-side gain, offset, lag, idle current) the logged currents are altered and the model
has every physics effect. Logs carry the measured (tracked) speeds and the reference pose
on a map (:attr:`Scenario.terrain`, a ramp for slope scenarios), so the diagnosis can look
up slopes and localise in space. Each scenario drives one ground (the physics model
under test has one ground); the catalogue as a whole covers several.

Withheld gap, measured with the truth simulator (seed 0, 5 runs x 20 s, default noise):
the whole-run charge change per side, ``|Q_truth - Q_without|`` summed over runs and
sides, as % of the charge and as a ratio to the noise's own effect on the charge, and the
per-sample RMS change over the noise's RMS (:func:`withheld_gap`):

=======================  ==================================  ========  =======  ======
scenario                 manoeuvre / ground                   charge %  / noise  RMS /n
=======================  ==================================  ========  =======  ======
turning_resistance       pivots_arcs / coated_wood              85.32    843.0   36.87
gear_losses              mixed / coated_wood                    16.35     85.0    5.15
coulomb_friction         mixed / snow_over_concrete             15.43     72.3    3.67
viscous_friction         speed_sweep / snow_over_concrete       12.01     29.6    1.57
inertia                  start_stop / coated_wood               27.17     51.6    9.23
static_friction          pivot_go / sand                         0.32      4.0    0.72
stribeck                 creep / sand                            7.10     31.8    1.55
longitudinal_slip        start_stop / snow                       2.35      7.3    1.38
lateral_slip             tight_arcs / snow                       1.31      8.7    0.98
speed_saturation         top_speed / snow_over_concrete          2.83      7.7    4.10
torque_saturation        pivots_arcs / asphalt                   3.34     43.2    3.51
slope                    hills / coated_wood                     9.25     47.7   10.36
mass                     mixed / snow_over_concrete             19.26    115.0    6.57
track_width              tight_arcs / coated_wood               29.78    258.9   21.26
rolling_resistance       mixed / snow_over_concrete              8.96     43.7    2.33
motor_constant           mixed / coated_wood                    12.70     80.9    4.62
quadratic_drag           speed_sweep / coated_wood              27.00     57.4    3.38
current_gain             mixed / coated_wood                     8.01     48.1    2.61
current_offset           mixed / coated_wood                     5.81     32.6    1.40
time_lag                 start_stop / coated_wood                0.13      0.2    9.31
idle_current             mixed / coated_wood                    17.29     89.9    4.02
=======================  ==================================  ========  =======  ======

``armature_heat``, ``sensor`` and ``control`` change power, not the drive currents: their
scenarios log battery voltage and pack current (:attr:`Scenario.power_logs`), their gap is
one of battery power (:attr:`WithheldGap.power`). Weak ones: static
friction acts only on the breakaway samples (4x the noise on the charge, below it per
sample); a time lag moves the current, not the charge (its RMS ratio shows it). The stock
Husky never reaches its torque limit, so that scenario drives one with an 8 A limit, and
in pivots, not climbs: the model under test predicts at zero slope, so a climb would
withhold slope too (``withheld_gap_ratio`` takes the larger of the charge and RMS ratios).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from energy import (
    EFFECTS,
    CurrentModel,
    GroundParams,
    InteractionLog,
    NoiseModel,
    PhysicsCurrentModel,
    RobotParams,
    TruthSimulator,
    ground_preset,
    robot_preset,
)
from energy.logs import at_rest
from energy.sim import PAPER_GROUNDS, measure_currents
from terrain.procedural import flat_map, ramp_map
from terrain.terrain_map import TerrainMap
from terrawatt_base.checks import check_choice, check_int, check_real, check_seed
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .manoeuvres import MANOEUVRES, manoeuvre_commands
from .power import PowerGap, battery_streams, power_gap

__all__ = ["MEASUREMENT_EFFECTS", "PARAMETER_EFFECTS", "LAW_EFFECTS", "POWER_ONLY_EFFECTS", "Scenario",
           "WithheldGap", "SCENARIOS", "scenario", "pair_scenario", "null_scenario", "withheld_gap",
           "withheld_gap_ratio"]

_DT_S = 0.01
_MAP_CELLS = 80  # square map (1 m cells); runs start at its centre
_DRIVE_EFFECTS = tuple(e for e in EFFECTS if e not in ("sensor", "control"))

#: Parameter-error effects and the truth's deviation from the model's nominal value.
PARAMETER_EFFECTS: dict[str, str] = {
    "mass": "15 kg payload: truth 65 kg, model 50 kg",
    "track_width": "effective track multiplier: truth 2.25, model 1.875",
    "rolling_resistance": "rolling resistance of the ground: truth 1.6 x the model's",
    "lateral_friction": "lateral friction of skid steering: truth 1.5 x the model's",
    "motor_constant": "torque constant: truth 0.85 x the model's (current / 0.85)",
    "rotor_inertia": "drivetrain inertia: truth 6 x the model's rotor inertia (a heavier gearbox and wheels)",
}
#: Resistance laws the truth's physics holds beyond the model's, and their size.
LAW_EFFECTS: dict[str, str] = {
    "quadratic_drag": "loose ground: a speed-squared drag of 12 N s^2/m^2 per side (12 N at 1 m/s)",
}
#: Measurement effects and how the truth logs are altered.
MEASUREMENT_EFFECTS: dict[str, str] = {
    "current_gain": "per-side current gain: left 1.12, right 0.92",
    "current_offset": "per-side current offset: left +0.25 A, right -0.15 A",
    "time_lag": "the current stream lags the drive stream by 0.12 s",
    "idle_current": "the model has no idle current (truth 0.59 A)",
    "rest_current": "standing still the sensor reads 0 (its deadband), the model its 0.59 A offset",
}
#: Catalogued effects no drive-current log can show, and why: their scenarios log battery power.
POWER_ONLY_EFFECTS: dict[str, str] = {"armature_heat": "copper loss changes the electrical power, not the motor current",
                                      "sensor": "the sensors draw no motor current",
                                      "control": "the control board draws no motor current"}


@dataclass(frozen=True)
class WithheldGap:
    """How much a scenario's withheld effects change its logs, against the noise.

    ``charge_change_mah``: sum over runs and sides of ``|Q_truth - Q_without|`` (clean
    currents); ``noise_charge_mah``: the same for the measurement noise (``|Q_measured -
    Q_clean|``); ``ratio`` their quotient. ``rms_change_a`` / ``noise_rms_a``: per-sample
    RMS of the same differences; ``rms_ratio`` their quotient. ``power``: the same for the
    battery power of a scenario with :attr:`Scenario.power_logs` (None otherwise).
    """

    scenario: str
    charge_mah: float
    charge_change_mah: float
    charge_change_pct: float
    noise_charge_mah: float
    ratio: float
    rms_change_a: float
    noise_rms_a: float
    rms_ratio: float
    power: PowerGap | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain dict."""
        return dataclasses.asdict(self)


def _rest(run: Any) -> np.ndarray:
    """Where a truth run stands still, from the speeds it drove (as its log reports them)."""
    t, v, w = run.log.time_s, run.actual_v_mps, run.actual_omega_radps
    return at_rest(v, w, np.gradient(v, t), np.gradient(w, t))


def _drag_current_a(robot: RobotParams, run: Any, drag_n_s2_per_m2: float) -> np.ndarray:
    """The signed motor current (N, 2) of a drag ``c v_s |v_s|`` per side on a truth run's tracked motion."""
    half = robot.track_width_multiplier * robot.track_width_m / 2.0
    v_side = run.actual_v_mps[:, None] + np.outer(run.actual_omega_radps, [-half, half])
    mo = robot.motor
    return drag_n_s2_per_m2 * v_side * np.abs(v_side) * robot.wheel_radius_m / (
        mo.gear_ratio * mo.gear_efficiency * mo.torque_constant_nm_per_a)


def _husky_variant(**motor: float) -> RobotParams:
    rb = robot_preset("husky")
    return rb.replace(motor=dataclasses.replace(rb.motor, **motor)) if motor else rb


@dataclass(frozen=True)
class Scenario:
    """Logs that excite the ``withheld`` effects and a model that lacks them.

    Parameters
    ----------
    name : str
    withheld : tuple of str
        Catalogued effect names the model lacks (physics effects from
        :data:`~energy.physics.EFFECTS`, or keys of :data:`PARAMETER_EFFECTS` /
        :data:`MEASUREMENT_EFFECTS`); empty for the null scenario.
    manoeuvre : str or tuple of str
        Key(s) of :data:`MANOEUVRES`; several alternate over the runs.
    robot, ground : RobotParams, GroundParams
        The truth's robot and ground.
    model_robot, model_ground : RobotParams or GroundParams, optional
        The model's (parameter errors); ``None`` = the truth's.
    grade : float
        Grade of the ramp map driven on (0 = flat).
    n_runs : int
        Runs per :meth:`make_logs` (>= 2).
    run_duration_s : float
        Length of each run (s), >= 5.
    noise : NoiseModel
        Measurement of the logged currents (idle current, noise, outliers, quantisation).
    current_gain, current_offset_a : (float, float)
        Per-side gain and offset applied to the truth currents (measurement effects).
    rest_shift_a : (float, float)
        Per-side shift of the truth currents where the robot stands still
        (:func:`energy.logs.at_rest` of the tracked speeds; a measurement effect).
    lag_s : float
        Delay of the current stream behind the drive stream (s).
    drag_n_s2_per_m2 : float
        The truth's speed-squared drag ``c v_s |v_s|`` per side (N s^2/m^2, >= 0; a law its physics lacks): its
        current ``c v_s |v_s| r / (N_g eta K_t)`` (the truth robot's gear and motor, the tracked side speeds) is
        added to each side's clean motor current.
    model_idle : bool
        The model is calibrated with the idle current (False for ``"idle_current"``).
    power_logs : bool
        The logs carry battery voltage and pack current; the model has the electronics unless withheld.
    excitable : bool
        Whether drive currents can show the withheld effects at all.
    note : str
    """

    name: str
    withheld: tuple[str, ...]
    manoeuvre: str | tuple[str, ...]
    robot: RobotParams = field(default_factory=lambda: robot_preset("husky"))
    ground: GroundParams = field(default_factory=lambda: PAPER_GROUNDS["coated_wood"])
    model_robot: RobotParams | None = None
    model_ground: GroundParams | None = None
    grade: float = 0.0
    n_runs: int = 5
    run_duration_s: float = 20.0
    noise: NoiseModel = field(default_factory=NoiseModel)
    current_gain: tuple[float, float] = (1.0, 1.0)
    current_offset_a: tuple[float, float] = (0.0, 0.0)
    rest_shift_a: tuple[float, float] = (0.0, 0.0)
    lag_s: float = 0.0
    drag_n_s2_per_m2: float = 0.0
    model_idle: bool = True
    power_logs: bool = False
    excitable: bool = True
    note: str = ""

    def __post_init__(self) -> None:
        own = "Scenario"
        if not isinstance(self.name, str) or not self.name:
            raise InvalidParameterError(f"Scenario.name must be a non-empty str, got {self.name!r}")
        if isinstance(self.withheld, str) or not all(isinstance(w, str) for w in self.withheld):
            raise InvalidParameterError(f"Scenario.withheld must be a tuple of effect names, got {self.withheld!r}")
        object.__setattr__(self, "withheld", tuple(self.withheld))
        known = set(EFFECTS) | set(PARAMETER_EFFECTS) | set(LAW_EFFECTS) | set(MEASUREMENT_EFFECTS)
        for w in self.withheld:
            if w not in known:
                raise UnknownNameError(f"withheld effect {w!r} is unknown; expected names from {sorted(known)!r}")
        mans = (self.manoeuvre,) if isinstance(self.manoeuvre, str) else tuple(self.manoeuvre)
        if not mans:
            raise InvalidParameterError("Scenario.manoeuvre must name at least one manoeuvre")
        for m in mans:
            check_choice("manoeuvre", m, MANOEUVRES)
        if not isinstance(self.robot, RobotParams) or not isinstance(self.ground, GroundParams):
            raise InvalidParameterError("Scenario.robot and .ground must be RobotParams and GroundParams")
        check_real("grade", self.grade, low=-1.0, high=1.0, owner=own)
        check_int("n_runs", self.n_runs, low=2, owner=own)
        check_real("run_duration_s", self.run_duration_s, low=5.0, high=600.0, owner=own)
        check_real("lag_s", self.lag_s, low=0.0, high=2.0, owner=own)
        check_real("drag_n_s2_per_m2", self.drag_n_s2_per_m2, low=0.0, owner=own)
        for k, pair in (("current_gain", self.current_gain), ("current_offset_a", self.current_offset_a),
                        ("rest_shift_a", self.rest_shift_a)):
            if len(tuple(pair)) != 2:
                raise InvalidParameterError(f"Scenario.{k} must be a pair (left, right), got {pair!r}")
            for v in pair:
                check_real(k, v, owner=own)
        if not isinstance(self.noise, NoiseModel):
            raise InvalidParameterError(f"Scenario.noise must be a NoiseModel, got {type(self.noise).__name__!r}")

    # ------------------------------------------------------------ derived
    @property
    def manoeuvres(self) -> tuple[str, ...]:
        """The manoeuvre of each kind of run, alternating over the runs."""
        return (self.manoeuvre,) if isinstance(self.manoeuvre, str) else tuple(self.manoeuvre)

    @property
    def model_effects(self) -> tuple[str, ...]:
        """Physics effects of the model under test (every drive effect, and with :attr:`power_logs` the
        electronics, but the withheld ones)."""
        return tuple(e for e in (EFFECTS if self.power_logs else _DRIVE_EFFECTS) if e not in self.withheld)

    @property
    def terrain(self) -> TerrainMap:
        """The map the runs drive on (flat, or a ramp rising along +x); pass it to the diagnosis."""
        shape = (_MAP_CELLS, _MAP_CELLS)
        if self.grade == 0.0:
            return flat_map(shape, 1.0, ground=self.ground.name)
        return ramp_map(shape, 1.0, self.grade, ground=self.ground.name)

    def true_values(self) -> dict[str, float]:
        """The truth's values by physical name (robot, motor and ground fields, measurement
        alterations), to compare fitted effect parameters with."""
        return self._values(self.robot, self.ground, self.noise.current_offset_a)

    def model_values(self) -> dict[str, float]:
        """The model's values by the same names (its nominal robot and ground, no alteration)."""
        out = self._values(self.model_robot or self.robot, self.model_ground or self.ground,
                           self.noise.current_offset_a if self.model_idle else 0.0)
        out.update(gain_left=1.0, gain_right=1.0, offset_left_a=0.0, offset_right_a=0.0, rest_left_a=0.0,
                   rest_right_a=0.0, lag_s=0.0)
        return out

    def _values(self, robot: RobotParams, ground: GroundParams, idle: float) -> dict[str, float]:
        out: dict[str, float] = {}
        for obj in (robot, robot.motor, ground):
            for f in dataclasses.fields(obj):
                v = getattr(obj, f.name)
                if isinstance(v, (int, float)) and not isinstance(v, bool):
                    out[f.name] = float(v)
        out["lateral_friction_coef"] = float(ground.effective_lateral_friction_coef)
        out.update(gain_left=float(self.current_gain[0]), gain_right=float(self.current_gain[1]),
                   offset_left_a=float(self.current_offset_a[0]), offset_right_a=float(self.current_offset_a[1]),
                   rest_left_a=float(self.rest_shift_a[0]), rest_right_a=float(self.rest_shift_a[1]),
                   lag_s=float(self.lag_s), idle_current_a=float(idle))
        return out

    # ------------------------------------------------------------ generation
    def _measure(self, motoring: np.ndarray, time_s: np.ndarray, seed: int, *, altered: bool,
                 idle: bool = True, rest: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        cur = motoring
        if altered:
            if self.lag_s > 0:
                cur = np.column_stack([np.interp(time_s - self.lag_s, time_s, cur[:, k]) for k in range(2)])
            cur = np.asarray(self.current_gain) * cur + np.asarray(self.current_offset_a)
            if rest is not None and any(self.rest_shift_a):
                cur = cur + rest[:, None] * np.asarray(self.rest_shift_a)
        noise = self.noise if idle else dataclasses.replace(self.noise, current_offset_a=0.0)
        streams = np.random.SeedSequence(seed).spawn(3)
        rngs = {k: np.random.default_rng(s) for k, s in zip(("current_noise", "outliers", "side_gain"), streams)}
        return measure_currents(noise, cur, rngs)

    def _silent_noise(self) -> NoiseModel:
        return NoiseModel(current_noise_std_a=0.0, outlier_rate=0.0, outlier_magnitude_a=0.0, quantisation_step_a=0.0,
                          current_offset_a=0.0, clip_negative=False, side_gain_std=0.0,
                          accel_noise_std_mps2=self.noise.accel_noise_std_mps2)

    def _runs(self, seed: int | None, *, world: str = "truth") -> list[tuple[Any, np.ndarray, int]]:
        """(truth run, motoring currents, run seed) of each run; ``world="model"`` uses the model's
        effects and parameters instead of the truth's."""
        seed = check_seed(seed)
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        robot, ground, effects = self.robot, self.ground, None
        if world == "model":
            robot = self.model_robot or self.robot
            ground = self.model_ground or self.ground
            effects = self.model_effects
        sim = TruthSimulator(robot, {self.ground.name: ground}, effects, noise=self._silent_noise(), seed=0)
        terrain = self.terrain
        out = []
        for k in range(self.n_runs):
            run_seed = int(np.random.SeedSequence([seed, k]).generate_state(1)[0])
            profile = manoeuvre_commands(self.manoeuvres[k % len(self.manoeuvres)], self.run_duration_s,
                                         seed=run_seed, start_xy_m=(_MAP_CELLS / 2.0, _MAP_CELLS / 2.0))
            run = sim.run_drive(terrain, profile, seed=run_seed)
            current = np.asarray(run.clean_current_a)
            if world == "truth" and self.drag_n_s2_per_m2 > 0:
                current = current + _drag_current_a(self.robot, run, self.drag_n_s2_per_m2)
            out.append((run, current, run_seed))
        return out

    def make_logs(self, seed: int | None = 0) -> list[InteractionLog]:
        """``n_runs`` truth logs (every physics effect on, measured currents, tracked speeds, poses).

        Raises
        ------
        InvalidParameterError
            A seed outside the seed rule.
        """
        logs = []
        for k, (run, motoring, run_seed) in enumerate(self._runs(seed)):
            log = run.log
            _, meas = self._measure(motoring, log.time_s, run_seed, altered=True, rest=_rest(run))
            notes = f"withheld-effect scenario {self.name!r}, run {k}; {log.meta.notes}"
            meta = dataclasses.replace(log.meta, velocity_source="measured", notes=notes)
            volts = amps = None
            if self.power_logs:
                _, _, volts, amps = battery_streams(self.noise, self.robot, run.breakdown.total_power_w, run_seed)
            logs.append(dataclasses.replace(log, v_mps=run.actual_v_mps, omega_radps=run.actual_omega_radps,
                                            current_left_a=meas[:, 0], current_right_a=meas[:, 1], meta=meta,
                                            battery_voltage_v=volts, battery_current_a=amps))
        return logs

    def calibration_log(self, seed: int | None = 0) -> InteractionLog:
        """A 5 s standstill log (sensor as calibrated: no measurement alteration)."""
        seed = check_seed(seed)
        seed = 0 if seed is None else seed
        sim = TruthSimulator(self.robot, {self.ground.name: self.ground}, noise=self._silent_noise(), seed=0)
        t = np.arange(500) * _DT_S
        run = sim.run_commands(t, np.zeros_like(t), np.zeros_like(t), ground=self.ground.name, seed=seed)
        _, meas = self._measure(np.asarray(run.clean_current_a), t, seed, altered=False)
        meta = dataclasses.replace(run.log.meta, velocity_source="measured", notes=f"calibration of {self.name!r}")
        return dataclasses.replace(run.log, current_left_a=meas[:, 0], current_right_a=meas[:, 1], meta=meta)

    def make_model(self, seed: int | None = 0) -> CurrentModel:
        """The model under test: a fitted :class:`~energy.PhysicsCurrentModel` lacking the
        withheld effects, its rest level calibrated on :meth:`calibration_log`."""
        robot = self.model_robot or self.robot
        if not self.model_idle:  # the model knows no rest level at all
            robot = robot.replace(rest_current_a=0.0)
        model = PhysicsCurrentModel(robot=robot, ground=self.model_ground or self.ground,
                                    fit_parameters=("rest_current_a",) if self.model_idle else (),
                                    effects=self.model_effects)
        return model.fit([self.calibration_log(seed)])


def withheld_gap(sc: Scenario, seed: int | None = 0) -> WithheldGap:
    """How much the withheld effects change ``sc``'s currents, against the noise (see :class:`WithheldGap`).

    The truth's clean currents (idle, clamp, measurement alterations) against the clean
    currents of a world that lacks the withheld effects (the model's effects, parameters,
    idle current, no alteration), run by run with the same seeds.

    Raises
    ------
    InvalidParameterError
        Not a Scenario, or a bad seed.
    """
    if not isinstance(sc, Scenario):
        raise InvalidParameterError(f"sc must be a Scenario, got {type(sc).__name__!r}")
    seed = 0 if check_seed(seed) is None else seed
    truth = sc._runs(seed)
    model = sc._runs(seed, world="model")
    q = dq = dn = sq_change = sq_noise = 0.0
    n = 0
    power = None
    if sc.power_logs:
        measured = [np.prod(battery_streams(sc.noise, sc.robot, r.breakdown.total_power_w, rs)[2:], axis=0)
                    for r, _, rs in truth]
        power = power_gap([np.asarray(r.breakdown.total_power_w) for r, _, _ in truth],
                          [np.asarray(r.breakdown.total_power_w) for r, _, _ in model], measured, _DT_S)
    for (run, mot, rs), (_, mot_m, _) in zip(truth, model):
        t = run.log.time_s
        clean, meas = sc._measure(mot, t, rs, altered=True, rest=_rest(run))
        clean_m, _ = sc._measure(mot_m, t, rs, altered=False, idle=sc.model_idle)
        to_mah = _DT_S / 3.6
        q += float(clean.sum()) * to_mah
        dq += float(np.abs((clean - clean_m).sum(axis=0)).sum()) * to_mah
        dn += float(np.abs((meas - clean).sum(axis=0)).sum()) * to_mah
        sq_change += float(((clean - clean_m) ** 2).sum())
        sq_noise += float(((meas - clean) ** 2).sum())
        n += clean.size
    rms_c, rms_n = (sq_change / n) ** 0.5, (sq_noise / n) ** 0.5
    return WithheldGap(sc.name, q, dq, 100.0 * dq / q if q > 0 else 0.0, dn, dq / dn if dn > 0 else float("inf"),
                       rms_c, rms_n, rms_c / rms_n if rms_n > 0 else float("inf"), power)


def withheld_gap_ratio(sc: Scenario, seed: int | None = 0) -> float:
    """How far the withheld effects stand above the noise: the largest of the charge ratio
    and the per-sample RMS ratio of :func:`withheld_gap` (an effect shows either as a bias
    of the whole-run charge, or in the shape of the current, as a lag does), and of the
    battery power's with :attr:`Scenario.power_logs`."""
    gap = withheld_gap(sc, seed)
    return max(gap.ratio, gap.rms_ratio, *((gap.power.ratio, gap.power.rms_ratio) if gap.power else ()))


def _make_scenarios() -> dict[str, Scenario]:
    wood, snow = PAPER_GROUNDS["coated_wood"], PAPER_GROUNDS["snow_over_concrete"]
    husky = robot_preset("husky")
    sand = ground_preset("sand")
    loose_snow = ground_preset("snow")
    s = [
        Scenario("turning_resistance", ("turning_resistance",), "pivots_arcs", ground=wood),
        Scenario("gear_losses", ("gear_losses",), "mixed", ground=wood),
        Scenario("coulomb_friction", ("coulomb_friction",), "mixed", ground=snow),
        Scenario("viscous_friction", ("viscous_friction",), "speed_sweep", ground=snow),
        Scenario("inertia", ("inertia",), "start_stop", ground=wood),
        Scenario("static_friction", ("static_friction",), "pivot_go", ground=sand, excitable=False,
                 note="the truth starts moving within one sample of a command, so the breakaway excess at "
                      "standstill never shows; it used to, only because a stopped robot crept on at a few "
                      "um/s with its breakaway force applied for the whole rest"),
        Scenario("stribeck", ("stribeck",), "creep", ground=sand),
        Scenario("longitudinal_slip", ("longitudinal_slip",), "start_stop", ground=loose_snow),
        Scenario("lateral_slip", ("lateral_slip",), "tight_arcs", ground=loose_snow),
        Scenario("speed_saturation", ("speed_saturation",), "top_speed", ground=snow),
        Scenario("torque_saturation", ("torque_saturation",), "pivots_arcs", ground=ground_preset("asphalt"),
                 robot=_husky_variant(max_torque_nm=0.044 * 8.0),
                 note="a Husky with an 8 A torque limit (the stock one never reaches its limit); pivots, "
                      "not climbs: the model under test predicts at zero slope, so a climb withholds slope too"),
        Scenario("slope", ("slope",), "hills", ground=wood, grade=0.15),
        Scenario("mass", ("mass",), "mixed", ground=snow, robot=husky.replace(mass_kg=65.0),
                 model_robot=husky),
        Scenario("track_width", ("track_width",), "tight_arcs", ground=wood,
                 robot=husky.replace(track_width_multiplier=2.25), model_robot=husky),
        Scenario("rolling_resistance", ("rolling_resistance",), "mixed", ground=snow.replace(
            rolling_resistance_coef=1.6 * snow.rolling_resistance_coef), model_ground=snow),
        Scenario("lateral_friction", ("lateral_friction",), "pivots_arcs", ground=wood.replace(
            lateral_friction_coef=1.5 * wood.effective_lateral_friction_coef), model_ground=wood),
        Scenario("motor_constant", ("motor_constant",), "mixed", ground=wood,
                 robot=_husky_variant(torque_constant_nm_per_a=0.85 * 0.044, back_emf_v_s_per_rad=0.85 * 0.044,
                                      max_torque_nm=0.85 * 0.044 * 30.0),
                 model_robot=husky),
        Scenario("rotor_inertia", ("rotor_inertia",), "start_stop", ground=wood,
                 robot=_husky_variant(rotor_inertia_kg_m2=6.0 * husky.motor.rotor_inertia_kg_m2), model_robot=husky),
        Scenario("quadratic_drag", ("quadratic_drag",), "speed_sweep", ground=wood, drag_n_s2_per_m2=12.0),
        Scenario("current_gain", ("current_gain",), "mixed", ground=wood, current_gain=(1.12, 0.92)),
        Scenario("current_offset", ("current_offset",), "mixed", ground=wood, current_offset_a=(0.25, -0.15)),
        Scenario("time_lag", ("time_lag",), "start_stop", ground=wood, lag_s=0.12),
        Scenario("idle_current", ("idle_current",), "mixed", ground=wood, model_idle=False),
        Scenario("rest_current", ("rest_current",), "start_stop", ground=wood, rest_shift_a=(-0.59, -0.59)),
    ]
    for name, why in POWER_ONLY_EFFECTS.items():
        s.append(Scenario(name, (name,), "pivots_arcs" if name == "armature_heat" else "mixed", ground=wood,
                          power_logs=True, note=why))
    return {sc.name: sc for sc in s}


#: Every single-effect scenario by the name of the effect it withholds.
SCENARIOS: dict[str, Scenario] = _make_scenarios()


def scenario(name: str) -> Scenario:
    """The single-effect scenario called ``name`` (an effect name).

    Raises
    ------
    UnknownNameError
        ``name`` is not a key of :data:`SCENARIOS` (the message lists them).
    """
    if not isinstance(name, str) or name not in SCENARIOS:
        raise UnknownNameError(f"scenario {name!r} is unknown; expected one of {sorted(SCENARIOS)!r}")
    return SCENARIOS[name]


def pair_scenario(a: str, b: str) -> Scenario:
    """Two effects withheld at once: ``a``'s ground, robot and map, runs alternating both manoeuvres.

    Raises
    ------
    UnknownNameError
        An unknown scenario name.
    InvalidParameterError
        ``a == b``, or either is not excitable or not a physics effect.
    """
    sa, sb = scenario(a), scenario(b)
    if a == b:
        raise InvalidParameterError(f"pair_scenario needs two different effects, got {a!r} twice")
    for sc in (sa, sb):
        if not sc.excitable or sc.power_logs or any(w not in EFFECTS for w in sc.withheld):
            raise InvalidParameterError(
                f"pair_scenario takes excitable physics effects; {sc.name!r} is not one"
            )
    grade = sa.grade or sb.grade
    return dataclasses.replace(sa, name=f"{a}+{b}", withheld=sa.withheld + sb.withheld,
                               manoeuvre=sa.manoeuvres + sb.manoeuvres, grade=grade, n_runs=6,
                               robot=sa.robot if sa.robot != robot_preset("husky") else sb.robot,
                               note=f"pair of {a} and {b}")


def null_scenario(manoeuvre: str = "mixed") -> Scenario:
    """Nothing withheld: the model equals the truth up to noise.

    Raises
    ------
    UnknownNameError
        An unknown manoeuvre.
    """
    check_choice("manoeuvre", manoeuvre, MANOEUVRES)
    return Scenario("null", (), manoeuvre, ground=PAPER_GROUNDS["snow_over_concrete"])
