"""Battery-power logs of the withheld-effect scenarios: the pack's voltage and current, and the power gap.

The scenarios of the electrical effects (armature heat, sensor and control power) log the
battery voltage and pack current: the total battery power of the truth (drive, sensors,
control board) drawn from a pack with the robot's nominal voltage behind
:data:`PACK_RESISTANCE_OHM`, measured with the scenario noise's battery terms on a random
stream of its own (the logged drive currents and every other stream stay as they were).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from energy import Battery, NoiseModel, RobotParams
from energy.sim import measure_battery

__all__ = ["PACK_RESISTANCE_OHM", "PowerGap", "scenario_battery", "battery_streams", "power_gap"]

#: Internal resistance of the scenarios' pack (ohm): a 24 V pack sags about 0.5 V at 10 A.
PACK_RESISTANCE_OHM = 0.05
# the battery stream is child 3 of SeedSequence(run_seed); children 0-2 measure the drive currents
_BATTERY_CHILD = 3


def scenario_battery(robot: RobotParams) -> Battery:
    """The scenarios' pack: the robot's nominal voltage behind :data:`PACK_RESISTANCE_OHM`."""
    return Battery(capacity_ah=20.0, voltage_v=robot.battery_voltage_v, internal_resistance_ohm=PACK_RESISTANCE_OHM)


def battery_streams(noise: NoiseModel, robot: RobotParams, total_power_w: Any,
                    run_seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Clean and measured battery voltage and pack current of one run (see :func:`energy.sim.measure_battery`)."""
    child = np.random.SeedSequence(run_seed).spawn(_BATTERY_CHILD + 1)[_BATTERY_CHILD]
    return measure_battery(noise, scenario_battery(robot), np.asarray(total_power_w, dtype=np.float64),
                           np.random.default_rng(child))


@dataclass(frozen=True)
class PowerGap:
    """How much withheld effects change the battery power, against the power's measurement noise.

    ``energy_wh``: the truth's battery energy; ``energy_change_wh``: sum over runs of
    ``|E_truth - E_without|``; ``noise_energy_wh``: the same for the measurement noise
    (``|E_measured - E_truth|``); ``ratio`` their quotient. ``rms_change_w`` /
    ``noise_rms_w``: per-sample RMS of the same differences; ``rms_ratio`` their quotient.
    """

    energy_wh: float
    energy_change_wh: float
    energy_change_pct: float
    noise_energy_wh: float
    ratio: float
    rms_change_w: float
    noise_rms_w: float
    rms_ratio: float


def power_gap(truth_w: Sequence[np.ndarray], without_w: Sequence[np.ndarray], measured_w: Sequence[np.ndarray],
              dt_s: float) -> PowerGap:
    """The :class:`PowerGap` of per-run battery powers: the truth's, a world without the withheld
    effects', and the measured one (voltage x pack current), all on one uniform clock of ``dt_s``."""
    e = de = dn = sq_c = sq_n = 0.0
    n = 0
    for p, q, m in zip(truth_w, without_w, measured_w):
        e += float(p.sum()) * dt_s / 3600.0
        de += abs(float((p - q).sum())) * dt_s / 3600.0
        dn += abs(float((m - p).sum())) * dt_s / 3600.0
        sq_c += float(((p - q) ** 2).sum())
        sq_n += float(((m - p) ** 2).sum())
        n += p.size
    rms_c, rms_n = (sq_c / max(n, 1)) ** 0.5, (sq_n / max(n, 1)) ** 0.5
    return PowerGap(e, de, 100.0 * de / e if e > 0 else 0.0, dn, de / dn if dn > 0 else float("inf"),
                    rms_c, rms_n, rms_c / rms_n if rms_n > 0 else float("inf"))
