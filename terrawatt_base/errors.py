"""The terrawatt exception hierarchy: one root, small subclasses that also inherit a builtin.

Every error the library raises on bad input derives from :class:`TerrawattError` and from
the builtin exception it resembles, so ``except ValueError`` keeps working for callers that
do not know terrawatt. Messages name the parameter, show the bad value with ``!r`` and say
what was expected.

The whole hierarchy lives here, in the groundwork every package builds on; ``terrain``,
``energy`` and ``planner`` raise and subclass these classes rather than start their own.
``terrain``, the package every user imports first, names all of them
(``from terrain import DataError``); ``energy`` and ``planner`` do not repeat them.
"""

from __future__ import annotations

__all__ = [
    "TerrawattError",
    "InvalidParameterError",
    "GridMismatchError",
    "OutOfBoundsError",
    "UnknownNameError",
    "FileFormatError",
    "FormatVersionError",
    "NotFittedError",
    "DataError",
    "UnitError",
    "NodataError",
    "PlanningError",
    "BlockedPositionError",
    "OptionalDependencyError",
    "TerrawattWarning",
    "DataRepairWarning",
    "RecoveryWarning",
    "FigureWarning",
    "ImplausibleDataWarning",
]


class TerrawattError(Exception):
    """Root of every exception raised by terrawatt.

    Parameters
    ----------
    *args
        The message (as for :class:`Exception`).
    parameter : str or tuple of str, optional
        The library parameter(s) the error is about, when there are (e.g. ``"risk"``), named so in
        the message (in backticks where the word also stands as prose: ```model```): a front end
        that calls them by other words (a command line's flags) renames them there, so the
        library never names a front end's words.

    Examples
    --------
    >>> err = InvalidParameterError("risk 0.1 lies below the median", parameter="risk")
    >>> err.parameter, str(err)
    ('risk', 'risk 0.1 lies below the median')
    """

    def __init__(self, *args: object, parameter: str | tuple[str, ...] | None = None) -> None:
        super().__init__(*args)
        self.parameter = parameter


class InvalidParameterError(TerrawattError, ValueError):
    """A parameter has a value outside its valid range (NaN, non-positive, wrong shape...)."""


class GridMismatchError(TerrawattError, ValueError):
    """Two rasters or layers that must share one grid do not."""


class OutOfBoundsError(TerrawattError, ValueError):
    """A position lies outside the map bounds."""


class UnknownNameError(TerrawattError, ValueError):
    """A name (layer, ground class, planner, model, effect) is not one of the known names."""


class FileFormatError(TerrawattError, OSError):
    """A file is corrupt, truncated or not of the expected format."""


class FormatVersionError(FileFormatError):
    """A file was written with a format version this release cannot read."""


class NotFittedError(TerrawattError, ValueError, AttributeError):
    """A model was used before ``fit`` (same contract as scikit-learn's NotFittedError)."""


class DataError(TerrawattError, ValueError):
    """Recorded data is unusable as given: unsorted or duplicated timestamps, NaNs, gaps,
    missing columns, empty files."""


class UnitError(DataError):
    """A quantity's magnitude contradicts its declared unit (e.g. mA declared as A)."""


class NodataError(InvalidParameterError, DataError):
    """A raster has nodata cells and the caller did not say how to fill them.

    ``n_nodata`` and ``n_cells`` count them, so a front end can phrase its own advice (a
    command line names its flag, the API its ``fill_nodata`` argument).
    """

    def __init__(self, message: str, *, n_nodata: int = 0, n_cells: int = 0,
                 parameter: str | tuple[str, ...] | None = None) -> None:
        super().__init__(message, parameter=parameter)
        self.n_nodata = n_nodata
        self.n_cells = n_cells


class PlanningError(TerrawattError, RuntimeError):
    """A planning problem cannot be set up or solved."""


class BlockedPositionError(PlanningError, ValueError):
    """A start or goal lies in an obstacle or on ground steeper than the slope limit."""


class OptionalDependencyError(TerrawattError, ImportError):
    """An optional dependency (an extra such as ``geo`` or ``ros``) is not installed."""


class TerrawattWarning(UserWarning):
    """Root of the warnings terrawatt emits.

    Parameters
    ----------
    *args
        The message (as for :class:`Warning`).
    parameter : str or tuple of str, optional
        The library parameter(s) the warning names, as :attr:`TerrawattError.parameter`.

    Examples
    --------
    >>> w = ImplausibleDataWarning("priced as unknown_ground", parameter="unknown_ground")
    >>> w.parameter, str(w)
    ('unknown_ground', 'priced as unknown_ground')
    """

    def __init__(self, *args: object, parameter: str | tuple[str, ...] | None = None) -> None:
        super().__init__(*args)
        self.parameter = parameter


class DataRepairWarning(TerrawattWarning):
    """Data was repaired because the caller asked for it (e.g. duplicates dropped)."""


class RecoveryWarning(TerrawattWarning):
    """A file left by an interrupted write was recovered (e.g. a registry moved back)."""


class FigureWarning(TerrawattWarning):
    """A figure was drawn other than asked because the data cannot show it (e.g. a spectrum
    band clipped to the IMU's Nyquist frequency); the results it shows are unaffected."""


class ImplausibleDataWarning(TerrawattWarning):
    """Data is readable and internally consistent but unlikely to be what the caller meant
    (e.g. a DEM whose cells are mostly steeper than 60 degrees); it is used as given."""
