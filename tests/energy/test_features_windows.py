"""Tests of energy.features.windows: WindowSpec in seconds and samples, window starts, sliding windows."""

import math

import numpy as np
import pytest

from energy.features import WindowSpec, sliding_windows, window_starts
from terrawatt_base.errors import DataError, InvalidParameterError


def test_paper_t_interval_is_ten_samples_at_100_hz():
    spec = WindowSpec.from_seconds(0.1, rate_hz=100.0)
    assert (spec.length_samples, spec.stride_samples) == (10, 10)
    assert WindowSpec.from_seconds() == spec  # the default t_interval
    assert spec.length_s == pytest.approx(0.1) and spec.stride_s == pytest.approx(0.1)


def test_window_in_seconds_at_the_borealtc_drive_rate():
    spec = WindowSpec.from_seconds(1.0, rate_hz=6.5, stride_s=0.1)
    assert spec.length_samples == 6  # round(6.5) to even
    assert spec.stride_samples == 1  # never below one sample
    assert spec.length_s == pytest.approx(6 / 6.5)


@pytest.mark.parametrize("kwargs", [dict(length_s=0.0, rate_hz=10.0), dict(length_s=1.0, rate_hz=-1.0),
                                    dict(length_s=1.0, rate_hz=10.0, stride_s=math.nan)])
def test_window_spec_rejects_bad_values(kwargs):
    with pytest.raises(InvalidParameterError, match=r"(length_s must be > 0|rate_hz must be > 0|stride_s must be finite)"):
        WindowSpec.from_seconds(**kwargs)
    with pytest.raises(InvalidParameterError, match="length_samples"):
        WindowSpec(0, 1, 10.0)


def test_window_starts_cover_the_end():
    spec = WindowSpec(length_samples=4, stride_samples=3, rate_hz=10.0)
    starts = window_starts(12, spec)
    assert starts.tolist() == [0, 3, 6, 8]
    covered = np.zeros(12, bool)
    for s in starts:
        covered[s : s + 4] = True
    assert covered.all()
    assert window_starts(4, spec).tolist() == [0]
    with pytest.raises(DataError, match="shorter than one window"):
        window_starts(3, spec)


def test_sliding_windows_content():
    x = np.arange(10.0)
    spec = WindowSpec(3, 3, 1.0)
    w = sliding_windows(x, spec)
    assert w.tolist() == [[0, 1, 2], [3, 4, 5], [6, 7, 8], [7, 8, 9]]
    two = sliding_windows(np.column_stack([x, -x]), spec)
    assert two.shape == (4, 3, 2) and two[1, 0, 1] == -3.0
