"""Tests of energy.params: validation, presets and lookups."""

from __future__ import annotations

import dataclasses

import pytest
from params_samples import sample_robot

from energy import (
    GROUND_PRESETS,
    ROBOT_PRESETS,
    GroundParams,
    ground_preset,
    robot_preset,
)
from terrain import InvalidParameterError, UnknownNameError


def test_paper_seed_preset_has_the_paper_constants() -> None:
    r = robot_preset("paper_seed")
    assert (r.mass_kg, r.wheel_radius_m, r.track_width_m) == (0.8, 0.03, 0.1)
    m = r.motor
    assert (m.torque_constant_nm_per_a, m.back_emf_v_s_per_rad) == (0.8693, 0.8883)
    assert (m.rotor_inertia_kg_m2, m.viscous_damping_nm_s_per_rad) == (0.038, 0.00075)
    assert (m.armature_resistance_ohm, m.armature_inductance_h) == (53.94, 1e-6)
    assert r.battery_voltage_v == 12.0 and r.sensor_power_w == 1.2
    assert (r.control_standby_power_w, r.control_startup_power_w) == (1.4, 2.4)
    # derived limits: stall torque and no-load speed of the 12 V motor
    assert m.max_torque_nm == pytest.approx(0.8693 * 12.0 / 53.94)
    assert m.max_speed_radps == pytest.approx(12.0 / 0.8883)
    assert r.drive_kind == "differential"


def test_clearpath_presets() -> None:
    jackal, husky = robot_preset("jackal"), robot_preset("husky")
    assert jackal.mass_kg == 17.0 and jackal.drive_kind == "skid_steer"
    assert jackal.driven_sides == 2 and jackal.track_width_multiplier == 1.5
    assert husky.drive_kind == "skid_steer" and husky.track_width_multiplier == 1.875
    assert husky.wheel_radius_m == 0.1651 and husky.battery_voltage_v == 24.0
    assert set(ROBOT_PRESETS) == {"paper_seed", "jackal", "husky"}


def test_ground_presets() -> None:
    needed = {"asphalt", "concrete", "stone", "grass", "gravel", "sand", "snow",
              "coated_wood", "flooring"}
    assert needed <= set(GROUND_PRESETS)
    stone = ground_preset("stone")
    assert (stone.static_friction_coef, stone.coulomb_friction_coef) == (1.0, 0.7)
    assert stone.stribeck_velocity_coef_s_per_m == 20.0
    assert ground_preset("sand").coulomb_friction_coef == 0.5
    # loose ground rolls harder than paved ground
    crr = {n: g.rolling_resistance_coef for n, g in GROUND_PRESETS.items()}
    assert crr["sand"] > crr["grass"] > crr["asphalt"]
    for name, g in GROUND_PRESETS.items():
        assert g.name == name


def test_a_preset_cannot_be_altered_through_a_returned_copy() -> None:
    """Changing a preset means a new, re-validated parameter set; the preset stays as it was."""
    husky = robot_preset("husky")
    heavier = dataclasses.replace(husky, mass_kg=husky.mass_kg + 20.0)
    assert heavier.mass_kg == husky.mass_kg + 20.0
    assert robot_preset("husky") == husky and robot_preset("husky").mass_kg != heavier.mass_kg
    with pytest.raises(InvalidParameterError, match="mass_kg"):
        dataclasses.replace(husky, mass_kg=-1.0)  # __post_init__ checks every replacement
    with pytest.raises(InvalidParameterError, match="rolling_resistance_coef must be a real number"):
        dataclasses.replace(ground_preset("sand"), rolling_resistance_coef="0.05")


@pytest.mark.parametrize(("lookup", "name"), [(robot_preset, "rover9000"),
                                              (ground_preset, "lava")])
def test_unknown_preset_lists_valid_names(lookup, name) -> None:
    with pytest.raises(UnknownNameError, match=rf"'{name}' is unknown.*expected one of"):
        lookup(name)


def test_unhashable_preset_name() -> None:
    with pytest.raises(UnknownNameError, match="robot preset"):
        robot_preset(["husky"])  # type: ignore[arg-type]


def test_defaults_follow_replacements() -> None:
    g = GroundParams(name="g", static_friction_coef=0.6, coulomb_friction_coef=0.5,
                     rolling_resistance_coef=0.01)
    assert g.effective_lateral_friction_coef == 0.5
    assert g.replace(coulomb_friction_coef=0.4).effective_lateral_friction_coef == 0.4
    assert g.replace(lateral_friction_coef=0.2).effective_lateral_friction_coef == 0.2
    r = sample_robot()
    assert r.effective_yaw_inertia_kg_m2 == pytest.approx(10.0 * (0.5**2 + 0.4**2) / 12.0)
    assert r.replace(mass_kg=20.0).effective_yaw_inertia_kg_m2 == pytest.approx(
        2 * r.effective_yaw_inertia_kg_m2)
    with pytest.raises(InvalidParameterError, match="mass_kg"):
        r.replace(mass_kg=-2.0)


def test_resolve_unknown_ground_names_a_preset_or_refuses_unknown_cells():
    import numpy as np

    from energy.params import resolve_unknown_ground
    from terrain import InvalidParameterError, TerrainMap, UnknownNameError, flat_map

    assert resolve_unknown_ground("sand", None) == "sand"
    assert resolve_unknown_ground("None", flat_map((3, 3), 1.0, ground="ice")) is None
    ground = np.zeros((4, 5), dtype=int)
    ground[0, :2] = -1
    holes = TerrainMap(np.zeros((4, 5)), 1.0, ground=ground, ground_names={0: "asphalt"})
    with pytest.raises(InvalidParameterError, match="unknown in 2 of 20 cells and unknown_ground none refuses") as err:
        resolve_unknown_ground("none", holes)
    assert err.value.parameter == "unknown_ground"
    with pytest.raises(InvalidParameterError, match="no ground classes, so unknown_ground none refuses every cell"):
        resolve_unknown_ground("none", None)
    with pytest.raises(UnknownNameError, match="unknown_ground must be a ground preset, .* or 'none'; got 'lava'"):
        resolve_unknown_ground("lava", holes)
    with pytest.raises(UnknownNameError):
        resolve_unknown_ground(3, holes)


# --------------------------------------------------------------------------- robot files
def test_a_robot_file_gives_back_the_robot_and_names_what_is_wrong(tmp_path):
    import json

    from energy.params import read_robot_file, robot_params, write_robot_file
    from terrain import FileFormatError, FormatVersionError

    rover = robot_preset("jackal").replace(name="rover", mass_kg=31.5, rest_current_a=0.4)
    path = write_robot_file(rover, tmp_path / "rover.json")
    document = json.loads(path.read_text())
    assert document["format"] == "terrawatt-robot" and document["format_version"] == 1
    assert read_robot_file(path) == rover == robot_params(str(path)) == robot_params(path)
    document["robot"]["motor"]["gear_ratio"] = -2.0
    (tmp_path / "bad.json").write_text(json.dumps(document))
    with pytest.raises(FileFormatError, match="bad.json.* holds no valid robot: .*gear_ratio"):
        read_robot_file(tmp_path / "bad.json")
    document["robot"]["motor"]["gear_ratio"] = 2.0
    document["robot"]["mass_lb"] = 70.0
    (tmp_path / "typo.json").write_text(json.dumps(document))
    with pytest.raises(FileFormatError, match=r"unknown field\(s\) \['mass_lb'\]"):
        robot_params(tmp_path / "typo.json")
    document["format_version"] = 2
    (tmp_path / "future.json").write_text(json.dumps(document))
    with pytest.raises(FormatVersionError):
        read_robot_file(tmp_path / "future.json")
    for odd in (1.9, True, "1", 1.0, None):  # never read as version 1 (issue 29)
        document["format_version"] = odd
        (tmp_path / "odd.json").write_text(json.dumps(document))
        with pytest.raises(FileFormatError, match="no valid format version"):
            read_robot_file(tmp_path / "odd.json")
    (tmp_path / "notes.json").write_text("{")
    with pytest.raises(FileFormatError, match="corrupt"):
        read_robot_file(tmp_path / "notes.json")
    with pytest.raises(FileFormatError, match="missing"):
        robot_params(tmp_path / "absent.json")


def test_a_robot_file_larger_than_the_memory_budget_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from energy.params import read_robot_file, write_robot_file
    from terrain import FileFormatError

    path = write_robot_file(robot_preset("husky"), tmp_path / "big.json")
    with open(path, "a") as fh:  # a sparse 8 GiB tail: nothing is allocated to make it
        fh.truncate(8 * 1024**3)
    with pytest.raises(FileFormatError, match="memory budget"):
        read_robot_file(path)


def test_robot_params_takes_presets_robots_and_robot_files_only():
    from energy.params import robot_params, write_robot_file

    assert robot_params("husky") is robot_preset("husky")
    jackal = robot_preset("jackal")
    assert robot_params(jackal) is jackal
    with pytest.raises(UnknownNameError, match=r"--robot 'rover' is neither a robot preset \(husky, jackal, "):
        robot_params("rover", name="--robot")
    with pytest.raises(InvalidParameterError, match="robot must be a RobotParams, a preset name or a robot file"):
        robot_params(3)
    with pytest.raises(InvalidParameterError, match="robot must be a RobotParams"):
        write_robot_file("husky", "x.json")
