"""energy.sim.presets: the paper's grounds, their variation and the vibration signatures by ground."""

from __future__ import annotations

import pytest

from energy import GROUND_PRESETS, GroundParams, TruthSimulator, ground_preset, robot_preset
from energy.sim import (
    PAPER_GROUNDS,
    PAPER_VARIATION,
    VIBRATION_PRESETS,
    GroundVariation,
    VibrationSignature,
    vibration_preset,
)
from terrain import UnknownNameError

HUSKY = robot_preset("husky")


def test_presets_cover_every_ground_preset() -> None:
    assert set(GROUND_PRESETS) | set(PAPER_GROUNDS) <= set(VIBRATION_PRESETS)
    sim = TruthSimulator(HUSKY, GROUND_PRESETS)
    assert sim.ground_names == tuple(GROUND_PRESETS)


def test_the_paper_grounds_and_their_variation():
    assert list(PAPER_GROUNDS) == ["coated_wood", "snow_over_stone_tiles", "snow_over_concrete"]
    assert PAPER_GROUNDS["coated_wood"] == ground_preset("coated_wood")
    for name, ground in PAPER_GROUNDS.items():
        assert isinstance(ground, GroundParams) and ground.name == name
    assert set(PAPER_VARIATION) == set(PAPER_GROUNDS)
    assert all(isinstance(v, GroundVariation) for v in PAPER_VARIATION.values())
    # varnished wood is the most uniform of the three
    wood, *snow = (PAPER_VARIATION[name].relative_std for name in PAPER_GROUNDS)
    assert wood < min(snow)


def test_vibration_preset_by_name():
    sig = vibration_preset("coated_wood")
    assert isinstance(sig, VibrationSignature) and sig is VIBRATION_PRESETS["coated_wood"]
    assert sig.peak_frequencies_hz == (11.0, 24.0)
    # the tiles' joint-passing line: 0.3 m tiles give 1 / 0.3 Hz per m/s
    tiles = vibration_preset("snow_over_stone_tiles")
    assert tiles.peak_shifts_hz_per_mps[0] == pytest.approx(1.0 / 0.3)


@pytest.mark.parametrize("bad", ["mud", 3, None])
def test_an_unknown_vibration_preset_lists_the_known_ones(bad):
    with pytest.raises(UnknownNameError, match=r"vibration preset .* is unknown; expected one of \['asphalt'"):
        vibration_preset(bad)
