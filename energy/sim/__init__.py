"""Truth simulator: synthetic interaction logs from the physics model, noise and ground vibration.

:class:`TruthSimulator` turns velocity commands (on the spot, :meth:`~TruthSimulator.simulate_commands`)
or a route over a :class:`~terrain.TerrainMap` (:meth:`~TruthSimulator.drive`) into an
:class:`~energy.logs.InteractionLog` that looks like a real robot's:

1. **Velocity tracking.** The drive follows the commands with a first-order lag
   (time constant ``velocity_time_constant_s``; ``scipy.signal.lfilter``); the robot is in
   steady motion at the first command when the record starts. Accelerations are the
   backward differences of the tracked velocities.
2. **Drive currents.** :class:`~energy.physics.PhysicsEnergyModel` (``effects`` switch its
   effects, so a log can hold an effect that a model under test lacks) gives the signed
   motor current ``I`` and motor speed ``omega_m`` of each side for the tracked motion, the
   slope along the heading and the ground of every sample. The logged current is the
   *motoring* current, ``I * sign(omega_m)`` (``|I|`` at ``omega_m = 0``): positive while
   the motor drives its wheels in either direction, negative while it is back-driven
   (braking). This is what the Husky driver reports in BorealTC: both sides draw current in
   a pivot turn and in reverse, the braked inner side of an arc reads 0.
3. **Ground variation** (optional, :class:`GroundVariation` per ground): a smooth random
   field over the distance travelled by the wheels scales the ground's resistance
   coefficients (rolling, viscous, lateral friction) — patchy snow, varying grass — and
   the broadband vibration with it.
4. **Measurement** (:class:`NoiseModel`): per-run side gains, idle current, Gaussian noise,
   positive outlier spikes, clipping of braking currents to 0 and quantisation. With a
   ``battery=``, also the pack's terminal voltage and the pack current that delivers the
   total battery power (drive, sensors, control board), with small white noise
   (:func:`measure_battery`, its own stream).
5. **Vertical vibration**: gravity ``g cos(tilt)`` plus, per ground, narrow spectral peaks
   (:class:`VibrationSignature`: frequencies, amplitudes growing with the wheel speed,
   optional speed-proportional shift for periodic ground such as tile joints) and a
   broadband roughness, plus accelerometer noise, at the IMU's own rate and timestamps.

Every random component draws from its own stream of ``numpy.random.SeedSequence(seed)``,
so the same seed gives the same log and switching one component off leaves the others'
draws unchanged. Presets: :data:`PAPER_GROUNDS` (the vibration-current paper's three
grounds), :data:`VIBRATION_PRESETS` (one signature per ground preset and paper ground; the
values are plausible, invented ones shaped after the paper's Fig. 7 and the BorealTC
IMU spectra — not measurements), :data:`PAPER_VARIATION`.
"""

from .noise import NoiseModel, measure_battery, measure_currents
from .presets import PAPER_GROUNDS, PAPER_VARIATION, VIBRATION_PRESETS, vibration_preset
from .run import TruthRun
from .simulator import TruthSimulator
from .variation import FACTOR_LOG_STEP, GroundVariation, variation_factor, varied_ground_table
from .vibration import VibrationSignature, vibration_accel_mps2

__all__ = [
    "TruthSimulator",
    "TruthRun",
    "NoiseModel",
    "VibrationSignature",
    "GroundVariation",
    "PAPER_GROUNDS",
    "PAPER_VARIATION",
    "VIBRATION_PRESETS",
    "vibration_preset",
    "measure_currents",
    "measure_battery",
    "variation_factor",
    "varied_ground_table",
    "vibration_accel_mps2",
    "FACTOR_LOG_STEP",
]
