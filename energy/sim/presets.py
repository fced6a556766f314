"""Truth-simulator presets: the vibration-current paper's grounds, their variation, vibration signatures."""

from __future__ import annotations

from terrawatt_base.errors import UnknownNameError

from ..params import GroundParams, ground_preset
from .variation import GroundVariation
from .vibration import VibrationSignature

__all__ = ["PAPER_GROUNDS", "PAPER_VARIATION", "VIBRATION_PRESETS", "vibration_preset"]


def _snow_over(name: str, mu_s: float, mu_k: float, crr: float, c_v: float, mu_lat: float) -> GroundParams:
    return GroundParams(name=name, static_friction_coef=mu_s, coulomb_friction_coef=mu_k,
                        stribeck_velocity_coef_s_per_m=20.0, viscous_friction_coef_s_per_m=c_v,
                        rolling_resistance_coef=crr, lateral_friction_coef=mu_lat,
                        longitudinal_slip_coef=0.06, lateral_slip_coef=0.08)


#: The vibration-current paper's three grounds. ``"coated_wood"`` is the library preset;
#: the two thin-snow grounds are estimates between the ``"snow"`` preset and the hard
#: surface underneath (more rolling resistance and less lateral grip than the bare
#: surface; tiles slightly rougher than concrete).
PAPER_GROUNDS: dict[str, GroundParams] = {
    "coated_wood": ground_preset("coated_wood"),
    "snow_over_stone_tiles": _snow_over("snow_over_stone_tiles", 0.45, 0.35, 0.045, 0.015, 0.35),
    "snow_over_concrete": _snow_over("snow_over_concrete", 0.40, 0.30, 0.040, 0.012, 0.30),
}

#: Ground variation of the paper's grounds (estimates): varnished wood is uniform, a thin
#: snow layer is patchy.
PAPER_VARIATION: dict[str, GroundVariation] = {
    "coated_wood": GroundVariation(relative_std=0.03, length_scale_m=3.0),
    "snow_over_stone_tiles": GroundVariation(relative_std=0.15, length_scale_m=1.5),
    "snow_over_concrete": GroundVariation(relative_std=0.20, length_scale_m=1.5),
}


def _sig(freqs: tuple[float, ...], amps: tuple[float, ...], rough: float, *,
         shifts: tuple[float, ...] | None = None, corner: float | None = None,
         width: float = 0.5) -> VibrationSignature:
    return VibrationSignature(peak_frequencies_hz=freqs, peak_amplitudes_mps2=amps,
                              peak_shifts_hz_per_mps=shifts, peak_width_hz=width,
                              roughness_mps2=rough, roughness_corner_hz=corner)


#: Vibration signatures by ground name (every :data:`~energy.params.GROUND_PRESETS` name and
#: every :data:`PAPER_GROUNDS` name), at the reference wheel speed 0.4 m/s. Invented but
#: plausible: RMS of 0.1–1 m/s^2 as in BorealTC's Husky IMU (flooring ~0.4, snow ~1.2 m/s^2
#: at ~0.2 m/s), hard smooth grounds with sharp structural peaks and little roughness,
#: soft grounds damped above a corner frequency, tiles with a joint-passing line
#: (0.3 m tiles: 3.33 Hz per m/s).
VIBRATION_PRESETS: dict[str, VibrationSignature] = {
    "asphalt": _sig((9.0, 18.0), (0.25, 0.15), 0.35),
    "concrete": _sig((10.0, 21.0), (0.20, 0.10), 0.25),
    "stone": _sig((7.0, 15.0), (0.35, 0.20), 0.50),
    "flooring": _sig((8.0, 14.0), (0.25, 0.20), 0.12),
    "coated_wood": _sig((11.0, 24.0), (0.15, 0.08), 0.10),
    "gravel": _sig((6.0, 27.0), (0.40, 0.20), 0.90),
    "grass": _sig((4.0,), (0.20,), 0.30, corner=15.0),
    "sand": _sig((3.0,), (0.15,), 0.25, corner=10.0),
    "snow": _sig((5.0, 12.0), (0.30, 0.20), 0.80, corner=20.0),
    "ice": _sig((10.0,), (0.10,), 0.08),
    "snow_over_stone_tiles": _sig((0.0, 7.5, 17.0), (0.50, 0.35, 0.25), 0.60,
                                  shifts=(1.0 / 0.3, 0.0, 0.0), corner=25.0),
    "snow_over_concrete": _sig((5.5, 14.0, 31.0), (0.30, 0.20, 0.10), 0.70, corner=20.0),
}


def vibration_preset(name: str) -> VibrationSignature:
    """The vibration signature preset of the ground called ``name``.

    Raises
    ------
    UnknownNameError
        ``name`` is not a key of :data:`VIBRATION_PRESETS` (the message lists them).

    Examples
    --------
    >>> vibration_preset("coated_wood").peak_frequencies_hz
    (11.0, 24.0)
    """
    try:
        return VIBRATION_PRESETS[name]
    except (KeyError, TypeError):
        raise UnknownNameError(
            f"vibration preset {name!r} is unknown; expected one of {sorted(VIBRATION_PRESETS)!r}"
        ) from None
