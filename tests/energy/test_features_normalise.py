"""Tests of energy.features.normalise: MinMaxNormaliser, the source ranges, fitted ranges."""

import math

import numpy as np
import pytest

from energy.features import SOURCE_CURRENT_RANGE_A, SOURCE_SPEED_RANGE_MPS, MinMaxNormaliser
from terrawatt_base.errors import DataError, InvalidParameterError


def test_source_ranges_with_absolute_values():
    speed = MinMaxNormaliser(*SOURCE_SPEED_RANGE_MPS, absolute=True)
    assert speed.transform(np.array([-0.5, 0.25, 1.5])).tolist() == [0.5, 0.25, 1.5]  # never clipped
    cur = MinMaxNormaliser(*SOURCE_CURRENT_RANGE_A)
    assert cur.transform(5.0) == pytest.approx(0.5)
    assert cur.inverse_transform(cur.transform(np.array([1.0, 7.0]))).tolist() == pytest.approx([1.0, 7.0])


def test_fitted_ranges_per_column_or_global():
    x = np.array([[0.0, 10.0, 3.0], [2.0, 20.0, 3.0]])
    per = MinMaxNormaliser.from_data(x)
    assert per.transform(x).tolist() == [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]  # constant column: shifted only
    glob = MinMaxNormaliser.from_data(x, per_column=False)
    assert glob.low.shape == () and glob.transform(x).max() == pytest.approx(1.0)
    again = MinMaxNormaliser.from_dict(per.to_dict())
    assert np.array_equal(again.transform(x), per.transform(x))


def test_normaliser_validates():
    with pytest.raises(InvalidParameterError, match="high >= low"):
        MinMaxNormaliser(1.0, 0.0)
    with pytest.raises(DataError, match="non-finite"):
        MinMaxNormaliser.from_data([1.0, math.nan])
    with pytest.raises(InvalidParameterError, match="keys"):
        MinMaxNormaliser.from_dict({"low": 0.0})
