"""energy.logs.meta: LogMeta, the run-level metadata of an interaction log."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from log_samples import make_log

from energy import LogMeta
from energy.logs.meta import VELOCITY_SOURCES
from terrain import InvalidParameterError


def test_defaults():
    meta = LogMeta()
    assert (meta.robot, meta.source, meta.ground_label, meta.velocity_source) == ("unknown", "synthetic", None, "commanded")
    assert (meta.track_width_m, meta.notes, meta.start_time_ns, meta.gravity_removed, meta.missing_currents) == (
        None, "", None, False, "")
    assert VELOCITY_SOURCES == ("commanded", "measured")


def test_values_are_normalised_and_frozen():
    meta = LogMeta(track_width_m=1, gravity_removed=np.bool_(True), start_time_ns=np.int64(5), velocity_source="measured")
    assert meta.track_width_m == 1.0 and isinstance(meta.track_width_m, float)
    assert meta.gravity_removed is True
    with pytest.raises(dataclasses.FrozenInstanceError):
        meta.robot = "x"  # type: ignore[misc]


def test_meta_validation():
    with pytest.raises(InvalidParameterError, match="velocity_source must be one of"):
        LogMeta(velocity_source="guessed")
    with pytest.raises(InvalidParameterError, match="track_width_m must be > 0"):
        LogMeta(track_width_m=0.0)
    with pytest.raises(InvalidParameterError, match="robot must be a str"):
        LogMeta(robot=3)
    with pytest.raises(InvalidParameterError, match="ground_label must be a non-empty str"):
        LogMeta(ground_label="")
    with pytest.raises(InvalidParameterError, match="meta must be a LogMeta"):
        make_log(meta={"robot": "x"})


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"source": None}, "LogMeta.source must be a str, got None"),
        ({"notes": 1}, "LogMeta.notes must be a str"),
        ({"missing_currents": b"x"}, "LogMeta.missing_currents must be a str"),
        ({"ground_label": 3}, "ground_label must be a non-empty str or None, got 3"),
        ({"track_width_m": float("nan")}, "track_width_m must be finite"),
        ({"start_time_ns": 1.5}, "LogMeta.start_time_ns must be an int or None, got 1.5"),
        ({"start_time_ns": True}, "LogMeta.start_time_ns must be an int or None, got True"),
        ({"gravity_removed": "yes"}, "LogMeta.gravity_removed must be a bool, got 'yes'"),
    ],
)
def test_more_bad_metadata_is_refused(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        LogMeta(**kwargs)
