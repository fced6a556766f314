"""The effect catalogue (energy.diagnosis.effects): names, lookup errors, effects from their specs."""

import pytest

from energy.diagnosis import EFFECTS_CATALOGUE, NOT_IDENTIFIABLE_FROM_CURRENT, effect, effect_from_spec
from energy.diagnosis.effects import resolve_effects
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def test_catalogue_names_every_drive_effect_and_lookup():
    for name in ("slope", "inertia", "turning_resistance", "gear_losses", "speed_saturation", "mass", "track_width",
                 "rolling_resistance", "motor_constant", "current_gain", "current_offset", "time_lag", "idle_current"):
        assert name in EFFECTS_CATALOGUE
        assert effect(name).name == name
    with pytest.raises(UnknownNameError, match="not in the catalogue"):
        effect("warp_drive")
    for name in NOT_IDENTIFIABLE_FROM_CURRENT:  # fitted on battery power, not on the currents
        assert name in EFFECTS_CATALOGUE and effect(name).kind == "electrical"
    with pytest.raises(InvalidParameterError, match="duplicate"):
        resolve_effects(["mass", "mass"])
    with pytest.raises(InvalidParameterError, match="must be a dict"):
        effect_from_spec("mass")


def test_effect_names_are_checked_before_any_work_naming_the_caller():
    from energy.diagnosis import check_effect_names

    assert check_effect_names(["mass", "idle_current"]) == ("mass", "idle_current")
    with pytest.raises(UnknownNameError, match=r"--effects \['warp_drive'\]: not in the catalogue"):
        check_effect_names(["mass", "warp_drive"], "--effects")
    with pytest.raises(InvalidParameterError, match="effects names an effect twice"):
        check_effect_names(["mass", "mass"])
    for bad in ("mass", [1, 2], None):
        with pytest.raises(InvalidParameterError, match="sequence of effect names"):
            check_effect_names(bad)
