"""The truth simulator: velocity commands or a route on a map -> a synthetic :class:`InteractionLog`.

The steps (velocity tracking, drive currents, ground variation, measurement, vertical
vibration) and the seeding are described in :mod:`energy.sim`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy import signal

from terrain.terrain_map import UNKNOWN_GROUND, TerrainMap
from terrawatt_base.checks import check_real, check_seed
from terrawatt_base.errors import (
    BlockedPositionError,
    InvalidParameterError,
    UnknownNameError,
)

from ..battery import Battery
from ..commands import CommandProfile, command_series, uniform_step_s
from ..ground import GroundParams
from ..logs import REST_OMEGA_RADPS, REST_SPEED_MPS, InteractionLog, LogMeta
from ..physics import EFFECTS, PhysicsEnergyModel
from ..profiles import terrain_along, waypoint_commands
from ..robot import GRAVITY_MPS2, RobotParams
from .noise import NoiseModel, measure_battery, measure_currents
from .presets import VIBRATION_PRESETS
from .run import TruthRun
from .variation import GroundVariation, variation_factor, varied_ground_table
from .vibration import VibrationSignature, vibration_accel_mps2

__all__ = ["TruthSimulator", "DEFAULT_NOISE"]

_LOG = logging.getLogger(__name__)

#: The measurement model of a :class:`TruthSimulator` built without ``noise=``.
DEFAULT_NOISE = NoiseModel()

# Independent random streams, in spawn order of SeedSequence(seed) (a new one goes last: the others keep their draws).
_STREAMS = ("current_noise", "outliers", "side_gain", "variation", "vibration", "accel_noise", "battery")


class TruthSimulator:
    """Synthesise interaction logs of a robot on named grounds, seeded.

    Parameters
    ----------
    robot : RobotParams
        The robot.
    grounds : mapping of str to GroundParams
        The grounds by name; the names are the labels of commands, logs and the map's
        ground classes.
    effects : iterable of str, optional
        Physics effects of the truth (names from :data:`~energy.physics.EFFECTS`);
        ``None`` = all. Passed to :class:`~energy.physics.PhysicsEnergyModel`.
    vibration : mapping of str to VibrationSignature, optional
        Signature of each ground (extra keys are ignored); ``None`` takes
        :data:`VIBRATION_PRESETS` by ground name.
    noise : NoiseModel
        Measurement model (default ``NoiseModel()``; ``NoiseModel.off()`` for clean logs).
    variation : mapping of str to GroundVariation, optional
        Ground variation by ground name; grounds without an entry are uniform.
    velocity_time_constant_s : float
        Time constant (>= 0) of the first-order velocity tracking; 0 = commands are
        followed exactly.
    current_rate_hz : float
        Drive-stream rate of :meth:`drive` (> 0), Hz.
    accel_rate_hz : float
        IMU rate (> 0), Hz; at least twice every vibration peak frequency.
    seed : int or None
        Default seed of every method (the seed rule: ``None`` or an int in [0, 2**32);
        ``None`` draws fresh entropy at each call); each method takes its own ``seed=`` too.
    battery : Battery, optional
        The pack: when given, the logs also carry its terminal voltage and the pack current
        that delivers the physics' total battery power (drive, sensors, control board), with
        the noise's battery terms (:func:`~energy.sim.noise.measure_battery`, its own random
        stream); ``None`` (default): the logs carry neither.

    Raises
    ------
    InvalidParameterError
        Bad types or values.
    UnknownNameError
        An unknown effect, or a ground without a vibration signature.

    Examples
    --------
    >>> from energy import robot_preset
    >>> from energy.sim import PAPER_GROUNDS
    >>> sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, seed=0)
    >>> log = sim.simulate_commands([0.0, 0.01, 0.02], [0.4] * 3, [0.0] * 3, ground="coated_wood")
    >>> len(log), log.meta.ground_label
    (3, 'coated_wood')
    """

    def __init__(
        self,
        robot: RobotParams,
        grounds: Mapping[str, GroundParams],
        effects: Sequence[str] | None = None,
        vibration: Mapping[str, VibrationSignature] | None = None,
        noise: NoiseModel = DEFAULT_NOISE,
        *,
        variation: Mapping[str, GroundVariation] | None = None,
        velocity_time_constant_s: float = 0.1,
        current_rate_hz: float = 100.0,
        accel_rate_hz: float = 100.0,
        seed: int | None = 0,
        battery: Battery | None = None,
    ) -> None:
        self.model = PhysicsEnergyModel(robot, effects)
        if battery is not None and not isinstance(battery, Battery):
            raise InvalidParameterError(f"battery must be None or a Battery, got {type(battery).__name__!r}")
        self.battery = battery
        self.robot = robot
        if not isinstance(grounds, Mapping) or not grounds:
            raise InvalidParameterError(f"grounds must be a non-empty mapping of name to GroundParams, got {grounds!r:.80}")
        for name, g in grounds.items():
            if not isinstance(name, str) or not name:
                raise InvalidParameterError(f"ground names must be non-empty str, got {name!r}")
            if not isinstance(g, GroundParams):
                raise InvalidParameterError(f"grounds[{name!r}] must be a GroundParams, got {type(g).__name__!r}")
        self.grounds: dict[str, GroundParams] = dict(grounds)
        self._names: tuple[str, ...] = tuple(self.grounds)
        source = VIBRATION_PRESETS if vibration is None else vibration
        if not isinstance(source, Mapping):
            raise InvalidParameterError(f"vibration must be a mapping of ground name to VibrationSignature, got {vibration!r:.80}")
        missing = [n for n in self._names if n not in source]
        if missing:
            where = "VIBRATION_PRESETS" if vibration is None else "vibration"
            raise UnknownNameError(
                f"no vibration signature for ground(s) {missing!r} in {where}; known: {sorted(source)!r} "
                "(pass vibration={name: VibrationSignature(...)})"
            )
        for n in self._names:
            if not isinstance(source[n], VibrationSignature):
                raise InvalidParameterError(f"vibration[{n!r}] must be a VibrationSignature, got {type(source[n]).__name__!r}")
        self.vibration: dict[str, VibrationSignature] = {n: source[n] for n in self._names}
        if not isinstance(noise, NoiseModel):
            raise InvalidParameterError(f"noise must be a NoiseModel, got {type(noise).__name__!r}")
        self.noise = noise
        var = {} if variation is None else variation
        if not isinstance(var, Mapping):
            raise InvalidParameterError(f"variation must be a mapping of ground name to GroundVariation, got {variation!r:.80}")
        for n, v in var.items():
            if not isinstance(v, GroundVariation):
                raise InvalidParameterError(f"variation[{n!r}] must be a GroundVariation, got {type(v).__name__!r}")
        self.variation: dict[str, GroundVariation] = {n: var[n] for n in self._names if n in var}
        own = "TruthSimulator"
        self.velocity_time_constant_s = check_real("velocity_time_constant_s", velocity_time_constant_s, low=0.0,
                                                   owner=own)
        self.current_rate_hz = check_real("current_rate_hz", current_rate_hz, low=0.0, low_inclusive=False, owner=own)
        self.accel_rate_hz = check_real("accel_rate_hz", accel_rate_hz, low=0.0, low_inclusive=False, owner=own)
        nyquist = self.accel_rate_hz / 2.0
        for n, sig in self.vibration.items():
            if any(f >= nyquist for f in sig.peak_frequencies_hz):
                raise InvalidParameterError(
                    f"vibration[{n!r}] has peaks at {sig.peak_frequencies_hz!r} Hz, not below the IMU's Nyquist "
                    f"frequency {nyquist!r} Hz (accel_rate_hz={self.accel_rate_hz!r})"
                )
        self.seed = check_seed(seed)

    def __repr__(self) -> str:
        return (f"TruthSimulator(robot={self.robot.name!r}, grounds={list(self._names)!r}, "
                f"effects={len(self.model.effects)} of the physics model's, seed={self.seed})")

    @property
    def effects(self) -> tuple[str, ...]:
        """The physics effects of the truth."""
        return self.model.effects

    @property
    def ground_names(self) -> tuple[str, ...]:
        """The ground names, in the order given."""
        return self._names

    # ---------------------------------------------------------------- public
    def run_commands(
        self,
        time_s: Any,
        v_cmd_mps: Any,
        omega_cmd_radps: Any,
        *,
        ground: str | Sequence[str] | np.ndarray,
        slope_rad: Any = 0.0,
        pose_xyh: Any = None,
        seed: int | None = None,
    ) -> TruthRun:
        """Simulate commands on the spot; the log with the noise-free truth behind it.

        Parameters
        ----------
        time_s : array_like, shape (N,)
            Uniformly spaced, strictly increasing times (s), N >= 2.
        v_cmd_mps, omega_cmd_radps : array_like, shape (N,)
            Commanded speed (m/s) and yaw rate (rad/s).
        ground : str or sequence of str
            One ground name for the whole run or one per sample.
        slope_rad : float or array_like, shape (N,)
            Pitch along the heading (positive uphill), in (-pi/2, pi/2).
        pose_xyh : array_like, shape (N, 3), optional
            Pose to store in the log.
        seed : int, optional
            Overrides the simulator's seed for this call.

        Returns
        -------
        TruthRun

        Raises
        ------
        InvalidParameterError
            Lengths that differ from ``time_s``, bad slopes or pose, fewer than 2 samples.
        DataError
            NaN/inf commands, times not uniformly spaced or not increasing.
        UnknownNameError
            A ground name that is not one of the simulator's grounds.
        """
        t = command_series("time_s", time_s, None)
        if t.size < 2:
            raise InvalidParameterError(f"time_s must hold at least 2 samples, got {t.size}")
        uniform_step_s("time_s", t)
        n = t.size
        v = command_series("v_cmd_mps", v_cmd_mps, n)
        w = command_series("omega_cmd_radps", omega_cmd_radps, n)
        gidx = self._ground_index(ground, n)
        try:
            slope = np.asarray(slope_rad, dtype=np.float64)
        except (TypeError, ValueError):
            slope = None
        if slope is None or slope.ndim > 1 or slope.size not in (1, n):
            raise InvalidParameterError(f"slope_rad must be a number or have {n} samples, got {slope_rad!r:.80}")
        slope = np.broadcast_to(slope, (n,)).astype(np.float64)
        if not np.all(np.isfinite(slope)) or np.any(np.abs(slope) >= np.pi / 2):
            raise InvalidParameterError("slope_rad must be finite and within (-pi/2, pi/2)")
        pose = None
        if pose_xyh is not None:
            try:
                pose = np.array(pose_xyh, dtype=np.float64)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"pose_xyh must be a numeric ({n}, 3) array, got {pose_xyh!r:.80}") from None
            if pose.shape != (n, 3):
                raise InvalidParameterError(f"pose_xyh must have shape ({n}, 3), got {pose.shape!r}")
        return self._simulate(t, v, w, gidx, slope, np.cos(slope), pose, self._seed(seed), "commands")

    def simulate_commands(self, time_s: Any, v_cmd_mps: Any, omega_cmd_radps: Any, *,
                          ground: str | Sequence[str] | np.ndarray, slope_rad: Any = 0.0,
                          pose_xyh: Any = None, seed: int | None = None) -> InteractionLog:
        """The :class:`InteractionLog` of :meth:`run_commands` (same parameters and errors).

        Examples
        --------
        >>> from energy import excitation_commands, robot_preset
        >>> from energy.sim import PAPER_GROUNDS
        >>> sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS)
        >>> p = excitation_commands(20.0, seed=1)
        >>> log = sim.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="snow_over_concrete", seed=7)
        >>> round(log.duration_s, 2), bool(log.current_left_a.min() >= 0)
        (19.99, True)
        """
        return self.run_commands(time_s, v_cmd_mps, omega_cmd_radps, ground=ground, slope_rad=slope_rad,
                                 pose_xyh=pose_xyh, seed=seed).log

    def run_drive(
        self,
        terrain: TerrainMap,
        route: Any,
        *,
        speed_mps: float = 0.5,
        accel_mps2: float = 0.5,
        turn_rate_radps: float | None = None,
        yaw_accel_radps2: float = 1.0,
        start_heading_rad: float | None = None,
        allow_obstacles: bool = False,
        seed: int | None = None,
    ) -> TruthRun:
        """Drive a route over a map; the log with the noise-free truth behind it.

        The route is either waypoints, turned into stop-turn-go commands by
        :func:`~energy.profiles.waypoint_commands` at ``current_rate_hz``, or a
        :class:`~energy.commands.CommandProfile` with a pose (e.g. from
        :meth:`CommandProfile.from_poses`). The pose is the reference the robot follows
        (path-tracking errors are not modelled; the velocity lag shapes the currents). At
        every pose the ground is the map's class of the cell (named by
        ``terrain.ground_names``); the pitch is ``arctan(grad_x cos h + grad_y sin h)`` and
        the tilt of the vertical ``arctan(|grad|)`` from the bilinearly interpolated
        gradients.

        Parameters
        ----------
        terrain : TerrainMap
        route : array_like (K, 2) or CommandProfile
            Waypoints (m) or a command profile with ``pose_xyh``.
        speed_mps, accel_mps2, yaw_accel_radps2, start_heading_rad
            Velocity profile of waypoint routes (see :func:`waypoint_commands`).
        turn_rate_radps : float, optional
            Pivot yaw rate; ``None`` = ``robot.turn_rate_radps``.
        allow_obstacles : bool
            Drive through obstacle cells instead of raising.
        seed : int, optional
            Overrides the simulator's seed for this call (use a new one per leg).

        Returns
        -------
        TruthRun
            Its log has ``pose_xyh`` and per-sample ``ground`` labels.

        Raises
        ------
        InvalidParameterError
            A bad route or profile parameters, a profile without a pose.
        OutOfBoundsError
            The route leaves the map.
        UnknownNameError
            The route crosses unknown ground (class -1) or a class whose name is not one
            of the simulator's grounds.
        BlockedPositionError
            The route crosses an obstacle cell (unless ``allow_obstacles``).
        """
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        if isinstance(route, CommandProfile):
            if route.pose_xyh is None:
                raise InvalidParameterError(
                    "route is a CommandProfile without pose_xyh; drive() needs the poses to look up the map "
                    "(build it with CommandProfile.from_poses or waypoint_commands)"
                )
            profile = route
        else:
            rate = self.robot.turn_rate_radps if turn_rate_radps is None else turn_rate_radps
            profile = waypoint_commands(route, speed_mps, accel_mps2=accel_mps2, turn_rate_radps=rate,
                                        yaw_accel_radps2=yaw_accel_radps2, dt_s=1.0 / self.current_rate_hz,
                                        start_heading_rad=start_heading_rad)
        pose = np.asarray(profile.pose_xyh)
        x, y, h = pose[:, 0], pose[:, 1], pose[:, 2]
        rows, cols, slope, cos_tilt = terrain_along(terrain, x, y, h)  # OutOfBoundsError off the map
        if not allow_obstacles:
            blocked = terrain.obstacle[rows, cols]
            if blocked.any():
                i = int(np.argmax(blocked))
                raise BlockedPositionError(
                    f"the route crosses an obstacle cell at ({x[i]!r}, {y[i]!r}) m (sample {i}); "
                    "pass allow_obstacles=True to drive through it"
                )
        gidx = self._map_ground_index(terrain, rows, cols, x, y)
        return self._simulate(np.asarray(profile.time_s), np.asarray(profile.v_mps), np.asarray(profile.omega_radps),
                              gidx, slope, cos_tilt, pose, self._seed(seed), "drive")

    def drive(self, terrain: TerrainMap, route: Any, *, speed_mps: float = 0.5, accel_mps2: float = 0.5,
              turn_rate_radps: float | None = None, yaw_accel_radps2: float = 1.0,
              start_heading_rad: float | None = None, allow_obstacles: bool = False,
              seed: int | None = None) -> InteractionLog:
        """The :class:`InteractionLog` of :meth:`run_drive` (same parameters and errors)."""
        return self.run_drive(terrain, route, speed_mps=speed_mps, accel_mps2=accel_mps2,
                              turn_rate_radps=turn_rate_radps, yaw_accel_radps2=yaw_accel_radps2,
                              start_heading_rad=start_heading_rad, allow_obstacles=allow_obstacles,
                              seed=seed).log

    # --------------------------------------------------------------- helpers
    def _seed(self, seed: int | None) -> int | None:
        return self.seed if seed is None else check_seed(seed)

    def _ground_index(self, ground: Any, n: int) -> np.ndarray:
        lookup = {name: k for k, name in enumerate(self._names)}
        if isinstance(ground, str):
            if ground not in lookup:
                raise UnknownNameError(f"ground {ground!r} is unknown; expected one of {list(self._names)!r}")
            return np.full(n, lookup[ground], dtype=np.intp)
        labels = np.asarray(ground)
        if labels.ndim != 1 or labels.size != n:
            raise InvalidParameterError(
                f"ground must be one name or one name per sample ({n}), got shape {labels.shape!r}"
            )
        if labels.dtype.kind not in "UO":
            raise InvalidParameterError(f"ground must hold str names, got dtype {labels.dtype!s}")
        uniq, inverse = np.unique(labels.astype(str), return_inverse=True)
        unknown = [u for u in uniq.tolist() if u not in lookup]
        if unknown:
            raise UnknownNameError(f"ground name(s) {unknown!r} are unknown; expected names from {list(self._names)!r}")
        return np.array([lookup[u] for u in uniq.tolist()], dtype=np.intp)[inverse.reshape(-1)]

    def _map_ground_index(self, terrain: TerrainMap, rows: np.ndarray, cols: np.ndarray,
                          x: np.ndarray, y: np.ndarray) -> np.ndarray:
        classes = np.asarray(terrain.ground[rows, cols], dtype=np.int64)
        names = terrain.ground_names
        lookup = {name: k for k, name in enumerate(self._names)}
        uniq, inverse = np.unique(classes, return_inverse=True)
        table = np.empty(uniq.size, dtype=np.intp)
        for j, cls in enumerate(uniq.tolist()):
            i = int(np.argmax(classes == cls))
            if cls == UNKNOWN_GROUND:
                raise UnknownNameError(
                    f"the route crosses unknown ground (class {UNKNOWN_GROUND}) at ({x[i]!r}, {y[i]!r}) m; "
                    "the truth simulator needs the ground of every cell it drives on"
                )
            name = names[cls]
            if name not in lookup:
                raise UnknownNameError(
                    f"the route crosses ground {name!r} (class {cls}) at ({x[i]!r}, {y[i]!r}) m, which is not one of "
                    f"the simulator's grounds {list(self._names)!r}"
                )
            table[j] = lookup[name]
        return table[inverse.reshape(-1)]

    def _track(self, cmd: np.ndarray, dt: float, still_below: float) -> tuple[np.ndarray, np.ndarray]:
        """First-order tracking (steady at the first command) and its backward derivative.

        Commanded to stop, the robot stops: once the tracked value of a zero command falls
        below ``still_below`` it is 0 (and so is its rate), instead of creeping towards 0 for
        ever with full Coulomb friction at a few mm/s. The rate is the unsnapped one
        elsewhere, so the stop adds no spike of acceleration.
        """
        tau = self.velocity_time_constant_s
        if tau > 0:
            a = math.exp(-dt / tau)
            zi = signal.lfiltic([1.0 - a], [1.0, -a], y=[cmd[0]], x=[cmd[0]])
            out, _ = signal.lfilter([1.0 - a], [1.0, -a], cmd, zi=zi)
        else:
            out = cmd.copy()
        rate = np.diff(out, prepend=out[0]) / dt
        still = (cmd == 0.0) & (np.abs(out) < still_below)
        out[still], rate[still] = 0.0, 0.0
        return out, rate

    def _simulate(self, t: np.ndarray, v_cmd: np.ndarray, w_cmd: np.ndarray, gidx: np.ndarray,
                  slope: np.ndarray, cos_tilt: np.ndarray, pose: np.ndarray | None, seed: int,
                  kind: str) -> TruthRun:
        n = t.size
        dt = float((t[-1] - t[0]) / (n - 1))
        ss = np.random.SeedSequence(seed)
        streams = dict(zip(_STREAMS, ss.spawn(len(_STREAMS))))
        rngs = {k: np.random.default_rng(s) for k, s in streams.items()}

        v, acc = self._track(v_cmd, dt, REST_SPEED_MPS)
        w, alpha = self._track(w_cmd, dt, REST_OMEGA_RADPS)
        half_track = self.robot.track_width_multiplier * self.robot.track_width_m / 2.0
        wheel_speed = np.maximum(np.abs(v), np.abs(w) * half_track)
        travel = np.concatenate(([0.0], np.cumsum(0.5 * (wheel_speed[1:] + wheel_speed[:-1]) * np.diff(t))))

        factor = variation_factor(gidx, travel, [self.variation.get(n) for n in self._names], streams["variation"])
        grounds = [self.grounds[n] for n in self._names]
        if self.variation:
            table, tidx, factor = varied_ground_table(grounds, gidx, factor)
        else:
            table, tidx = grounds, gidx
        res = self.model.power(v, w, table, accel_mps2=acc, alpha_radps2=alpha, slope_rad=slope,
                               time_s=t, ground_index=tidx)
        current = np.asarray(res.motor_current_a)
        omega_m = np.asarray(res.motor_speed_radps)
        motoring = np.where(omega_m != 0, current * np.sign(omega_m), np.abs(current))
        clean, measured = measure_currents(self.noise, motoring, rngs)

        m = int(math.floor((t[-1] - t[0]) * self.accel_rate_hz + 1e-9)) + 1
        ta = t[0] + np.arange(m, dtype=np.float64) / self.accel_rate_hz
        speed_a = np.interp(ta, t, wheel_speed)
        held = np.clip(np.searchsorted(t, ta + 1e-9, side="right") - 1, 0, n - 1)
        accel_z = GRAVITY_MPS2 * np.interp(ta, t, cos_tilt)
        signatures = [(g, self.vibration[g], self.variation[g].vibration_coupling if g in self.variation else 0.0)
                      for g in self._names]
        accel_z = accel_z + vibration_accel_mps2(speed_a, gidx[held], np.interp(ta, t, factor), signatures,
                                                 self.accel_rate_hz, streams["vibration"])
        if self.noise.accel_noise_std_mps2 > 0:
            accel_z = accel_z + self.noise.accel_noise_std_mps2 * rngs["accel_noise"].standard_normal(m)

        labels = np.asarray(self._names)[gidx]
        used = list(dict.fromkeys(labels.tolist()))
        withheld = [e for e in EFFECTS if e not in self.model.effects]
        notes = [f"truth simulator ({kind}), seed {seed}, velocity lag {self.velocity_time_constant_s:g} s"]
        if withheld:
            notes.append(f"effects off: {', '.join(withheld)}")
        if self.variation:
            notes.append("ground variation: " + ", ".join(
                f"{g} {self.variation[g].relative_std:g}" for g in used if g in self.variation))
        for flag, what in ((res.saturated, "saturated"), (res.traction_exceeded, "beyond traction")):
            count = int(np.count_nonzero(flag))
            if count:
                notes.append(f"{count} sample(s) {what}")
                _LOG.info("truth simulator: %d of %d samples %s", count, n, what)
        meta = LogMeta(robot=self.robot.name, source="synthetic", ground_label=used[0] if len(used) == 1 else None,
                       velocity_source="commanded", notes="; ".join(notes))
        volts = amps = None
        if self.battery is not None:
            _, _, volts, amps = measure_battery(self.noise, self.battery, np.asarray(res.total_power_w),
                                                rngs["battery"])
        log = InteractionLog(t, v_cmd, w_cmd, measured[:, 0], measured[:, 1], ta, accel_z,
                             pose_xyh=pose, ground=labels, meta=meta, battery_voltage_v=volts, battery_current_a=amps)
        return TruthRun(log=log, breakdown=res, actual_v_mps=v, actual_omega_radps=w, accel_mps2=acc,
                        alpha_radps2=alpha, slope_rad=slope, resistance_factor=factor, clean_current_a=clean)


