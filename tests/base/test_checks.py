"""One validator per kind of argument: what each accepts and what it refuses, by name."""

from __future__ import annotations

import math

import numpy as np
import pytest

from terrain import InvalidParameterError, UnknownNameError
from terrawatt_base.checks import (
    SEED_LIMIT,
    check_bool,
    check_choice,
    check_int,
    check_optional_real,
    check_real,
    check_seed,
    check_text,
    fmt_number,
    readonly,
    real_array,
)


@pytest.mark.parametrize("value", [0.5, 1, np.float32(0.5), np.int64(3), np.array(2.0)])
def test_check_real_accepts_real_numbers(value) -> None:
    assert check_real("x", value) == float(value)


@pytest.mark.parametrize(
    "value, pattern",
    [
        ("fast", r"speed_mps must be a real number, got 'fast' \(str\)"),
        (None, r"speed_mps must be a real number, got None"),
        (True, r"speed_mps must be a real number, got True \(bool\)"),
        (np.bool_(True), r"speed_mps must be a real number"),
        ([1.0], r"speed_mps must be a real number"),
        (math.nan, r"speed_mps must be finite"),
        (math.inf, r"speed_mps must be finite"),
    ],
)
def test_check_real_names_the_parameter(value, pattern) -> None:
    with pytest.raises(InvalidParameterError, match=pattern):
        check_real("speed_mps", value)


def test_check_real_bounds_and_owner() -> None:
    assert check_real("x", 0.0, low=0.0) == 0.0
    with pytest.raises(InvalidParameterError, match=r"x must be > 0, got 0.0"):
        check_real("x", 0.0, low=0.0, low_inclusive=False)
    with pytest.raises(InvalidParameterError, match=r"RobotParams.mass_kg must be <= 1000"):
        check_real("mass_kg", 1e4, high=1000.0, owner="RobotParams")
    with pytest.raises(InvalidParameterError, match=r"x must be < 1, got 1.0"):
        check_real("x", 1.0, high=1.0, high_inclusive=False)
    assert check_optional_real("x", None, low=0.0) is None
    assert check_optional_real("x", 2, low=0.0) == 2.0


def test_check_int() -> None:
    assert check_int("n", np.int32(4), low=1) == 4
    for bad in (4.0, "4", True, None):
        with pytest.raises(InvalidParameterError, match="n must be an integer"):
            check_int("n", bad)
    with pytest.raises(InvalidParameterError, match="n must be >= 1, got 0"):
        check_int("n", 0, low=1)
    with pytest.raises(InvalidParameterError, match="n must be <= 3, got 4"):
        check_int("n", 4, high=3)


def test_one_seed_rule() -> None:
    assert check_seed(None) is None
    assert check_seed(0) == 0 and check_seed(SEED_LIMIT - 1) == SEED_LIMIT - 1
    assert check_seed(np.uint32(7)) == 7
    for bad in (-1, SEED_LIMIT, 1.0, "1", True):
        with pytest.raises(InvalidParameterError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
            check_seed(bad)
    with pytest.raises(InvalidParameterError, match="^rng_seed must be"):
        check_seed(-5, name="rng_seed")


def test_text_choice_bool() -> None:
    assert check_text("name", "husky") == "husky"
    for bad in ("", "   ", 3, None):
        with pytest.raises(InvalidParameterError, match="name must be a non-empty string"):
            check_text("name", bad)
    assert check_choice("planner", "lattice", ("lattice", "RRTstar")) == "lattice"
    with pytest.raises(UnknownNameError, match=r"planner must be one of \['lattice', 'RRTstar'\], got 'PRM'"):
        check_choice("planner", "PRM", ("lattice", "RRTstar"))
    assert check_bool("refine", np.bool_(False)) is False
    with pytest.raises(InvalidParameterError, match="refine must be True or False"):
        check_bool("refine", "no")


def test_real_array_is_a_new_checked_array() -> None:
    src = np.arange(4.0)
    out = real_array("z", src, ndim=1)
    out[0] = 99.0
    assert src[0] == 0.0  # a copy: the caller's array is never altered
    for bad in (["a", "b"], ["0.5"], [1.0, None], [[1.0], [1.0, 2.0]], [1j], [True]):
        with pytest.raises(InvalidParameterError, match=r"z must be a real number or an array of them"):
            real_array("z", bad)
    with pytest.raises(InvalidParameterError, match=r"z must be a 2-D array, got shape \(4,\)"):
        real_array("z", src, ndim=2)
    with pytest.raises(InvalidParameterError, match=r"z has 1 NaN/inf entries of 4"):
        real_array("z", [0.0, np.nan, 1.0, 2.0])
    assert np.isnan(real_array("z", [np.nan], finite=False)[0])


def test_readonly_copies_and_locks() -> None:
    src = np.zeros(3)
    out = readonly(src, dtype=np.float32)
    assert out.dtype == np.float32 and not out.flags.writeable
    src[0] = 1.0
    assert out[0] == 0.0


def test_numbers_are_rounded_for_people() -> None:
    assert fmt_number(49.000000000001066) == "49"
    assert fmt_number(7) == "7"
    assert fmt_number(math.inf) == "inf"
    assert fmt_number(0.000123456) == "0.0001235"


def test_an_int_beyond_float_range_is_not_finite() -> None:
    with pytest.raises(InvalidParameterError, match="x must be finite"):
        check_real("x", 10**400)


def test_messages_show_numpy_scalars_as_plain_numbers():
    import numpy as np

    from terrawatt_base.checks import check_int, check_real

    with pytest.raises(InvalidParameterError, match=r"^speed must be <= 5, got 10\.0$"):
        check_real("speed", np.float64(10.0), high=5.0)
    with pytest.raises(InvalidParameterError, match=r"^n must be >= 1, got 0$"):
        check_int("n", np.int64(0), low=1)
    with pytest.raises(InvalidParameterError, match=r"got 'x' \(str\)$"):
        check_real("speed", "x")
