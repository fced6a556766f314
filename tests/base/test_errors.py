"""The exception hierarchy: one root, each subclass also the builtin it resembles; warnings apart."""

from __future__ import annotations

import warnings

import pytest

from terrawatt_base import errors
from terrawatt_base.errors import (
    BlockedPositionError,
    DataError,
    DataRepairWarning,
    FigureWarning,
    FileFormatError,
    FormatVersionError,
    GridMismatchError,
    ImplausibleDataWarning,
    InvalidParameterError,
    NodataError,
    NotFittedError,
    OptionalDependencyError,
    OutOfBoundsError,
    PlanningError,
    RecoveryWarning,
    TerrawattError,
    TerrawattWarning,
    UnitError,
    UnknownNameError,
)

#: Each error class and the builtins (or terrawatt parents) it must also be.
EXPECTED_BASES = {
    InvalidParameterError: (ValueError,),
    GridMismatchError: (ValueError,),
    OutOfBoundsError: (ValueError,),
    UnknownNameError: (ValueError,),
    FileFormatError: (OSError,),
    FormatVersionError: (FileFormatError, OSError),
    NotFittedError: (ValueError, AttributeError),
    DataError: (ValueError,),
    UnitError: (DataError, ValueError),
    NodataError: (InvalidParameterError, DataError, ValueError),
    PlanningError: (RuntimeError,),
    BlockedPositionError: (PlanningError, RuntimeError, ValueError),
    OptionalDependencyError: (ImportError,),
}


@pytest.mark.parametrize("cls", list(EXPECTED_BASES), ids=lambda c: c.__name__)
def test_every_error_derives_from_the_root_and_its_builtin(cls):
    assert issubclass(cls, TerrawattError)
    for base in EXPECTED_BASES[cls]:
        assert issubclass(cls, base)


@pytest.mark.parametrize("cls", list(EXPECTED_BASES), ids=lambda c: c.__name__)
def test_a_caller_that_knows_only_the_builtin_catches_the_error(cls):
    builtin = EXPECTED_BASES[cls][-1]
    with pytest.raises(builtin, match="bad value 3"):
        raise cls("bad value 3")


def test_the_root_is_an_exception_and_not_a_warning():
    assert issubclass(TerrawattError, Exception)
    assert not issubclass(TerrawattError, Warning)


@pytest.mark.parametrize(
    "cls", [DataRepairWarning, RecoveryWarning, FigureWarning, ImplausibleDataWarning], ids=lambda c: c.__name__
)
def test_warnings_have_their_own_root_under_userwarning(cls):
    assert issubclass(cls, TerrawattWarning)
    assert issubclass(cls, UserWarning)
    assert not issubclass(cls, TerrawattError)
    with pytest.warns(TerrawattWarning, match="repaired"):
        warnings.warn("data repaired", cls, stacklevel=1)


def test_nodata_error_counts_cells_and_keeps_its_message():
    exc = NodataError("3 of 12 cells are nodata", n_nodata=3, n_cells=12)
    assert (exc.n_nodata, exc.n_cells) == (3, 12)
    assert str(exc) == "3 of 12 cells are nodata"
    assert (NodataError("no count").n_nodata, NodataError("no count").n_cells) == (0, 0)


def test_everything_in_all_exists_and_is_an_error_or_a_warning():
    for name in errors.__all__:
        obj = getattr(errors, name)
        assert issubclass(obj, (TerrawattError, TerrawattWarning)), name


def test_terrain_re_exports_the_same_classes():
    import terrain

    for cls in (*EXPECTED_BASES, TerrawattError, TerrawattWarning, DataRepairWarning, RecoveryWarning):
        assert getattr(terrain, cls.__name__) is cls
