"""The frequency band of the vibration features: its validation and whether an IMU stream can serve it."""

from __future__ import annotations

from typing import Any

from terrawatt_base.checks import check_real, fmt_number
from terrawatt_base.errors import DataError, InvalidParameterError

from .spectra import NYQUIST_TOLERANCE

__all__ = ["DEFAULT_BAND_HZ", "BandNotServedError", "check_band_hz", "check_model_band", "band_served", "require_band"]

#: Default band of the vibration features (Hz): served by every IMU of 25 Hz or more
#: (the Husky's 30 Hz, the Jackal's 50 Hz, BorealTC's 100 Hz). On the BorealTC logs
#: (leave-one-run-out per ground, benchmarks/estimator_ablation.py) it scores within one
#: seed's spread of 1-50 Hz: whole-run median 8.9 % against 11.5 %, p90 32.6 % against
#: 29.6 %, 8 s sections 18.9 % against 17.9 %, RMSE 2.52 A against 2.50 A.
DEFAULT_BAND_HZ = (1.0, 12.0)


class BandNotServedError(DataError):
    """An acceleration stream is too slow for a band: the band reaches above its Nyquist frequency."""


def check_band_hz(band_hz: Any, name: str = "band_hz") -> tuple[float, float]:
    """A validated frequency band ``(low_hz, high_hz)`` with ``0 <= low_hz < high_hz``, finite.

    ``low_hz == 0`` starts the band at the first non-zero frequency bin (the mean of every
    segment is removed, so 0 Hz carries nothing).

    Raises
    ------
    InvalidParameterError
        Not a pair of real numbers; a NaN, infinite or negative edge; ``low_hz >= high_hz``.

    Examples
    --------
    >>> check_band_hz([1, 12])
    (1.0, 12.0)
    >>> check_band_hz((12.0, 1.0))
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: band_hz must be (low_hz, high_hz) with low_hz < high_hz, got (12.0, 1.0)
    """
    if isinstance(band_hz, (str, bytes)) or not hasattr(band_hz, "__len__") or len(band_hz) != 2:
        raise InvalidParameterError(f"{name} must be a pair (low_hz, high_hz) of frequencies in Hz, got {band_hz!r:.80}",
                                    parameter=name)
    try:
        low = check_real(f"{name}[0] (low_hz)", band_hz[0], low=0.0)
        high = check_real(f"{name}[1] (high_hz)", band_hz[1], low=0.0, low_inclusive=False)
    except InvalidParameterError as exc:  # the error is about the band: a front end says it by its own word
        raise InvalidParameterError(str(exc), parameter=name) from None
    if not low < high:
        raise InvalidParameterError(f"{name} must be (low_hz, high_hz) with low_hz < high_hz, got ({low!r}, {high!r})",
                                    parameter=name)
    return (low, high)


def check_model_band(model: Any, band_hz: Any, name: str = "band_hz", label: str = "model") -> None:
    """Refuse a model whose vibration band does not lie within ``band_hz`` (the band the logs' IMU serves).

    Parameters
    ----------
    model : CurrentModel
        A fitted model; only the estimator and paper models (``config_.band_hz``) have a band.
    band_hz : (float, float) or None
        The band the IMU serves (validated as :func:`check_band_hz`); None checks nothing.
    name : str
        How messages name ``band_hz`` (e.g. a flag).
    label : str
        How messages name the model (e.g. its file).

    Raises
    ------
    InvalidParameterError
        A bad ``band_hz``; a band for a model without one.
    BandNotServedError
        The model's band reaches outside ``band_hz`` (the message says how to retrain it).

    Examples
    --------
    >>> check_model_band(object(), None)
    """
    if band_hz is None:
        return
    lo_served, hi_served = check_band_hz(band_hz, name)
    config = getattr(model, "config_", None)
    if config is None or not hasattr(config, "band_hz"):
        raise InvalidParameterError(f"{name} applies to estimator and paper model files; {label!r} holds a "
                                    f"{type(model).__name__}", parameter=name)
    lo, hi = config.band_hz
    if lo < lo_served or hi > hi_served:
        raise BandNotServedError(
            f"the model {label!r} was trained on the vibration band {lo:g}-{hi:g} Hz, which does not lie within "
            f"{name} {lo_served:g} {hi_served:g}; train it again with a band_hz inside that band",
            parameter=tuple(dict.fromkeys((name, "band_hz")))
        )


def band_served(top_hz: float, rate_hz: float) -> bool:
    """Whether a stream sampled at ``rate_hz`` holds frequencies up to ``top_hz``.

    True when ``top_hz`` does not exceed the Nyquist frequency ``rate_hz / 2`` by more than
    :data:`~energy.features.NYQUIST_TOLERANCE` (a 99.5 Hz IMU serves 50 Hz).

    Examples
    --------
    >>> band_served(12.0, 30.0), band_served(49.0, 50.0)
    (True, False)
    """
    return float(top_hz) <= float(rate_hz) / 2.0 * (1.0 + NYQUIST_TOLERANCE)


def require_band(band_hz: Any, top_hz: float, rate_hz: float, where: str = "the acceleration stream") -> None:
    """Refuse a stream that cannot serve a model's band, naming the band, the rate and the fix.

    Parameters
    ----------
    band_hz : (float, float)
        The band the model was trained on (named in the message).
    top_hz : float
        The highest frequency the model's features use (Hz).
    rate_hz : float
        Sampling rate of the acceleration stream (Hz).
    where : str
        The stream, for the message (e.g. the run's source).

    Raises
    ------
    BandNotServedError
        ``top_hz`` lies above the stream's Nyquist frequency (see :func:`band_served`).
    """
    if band_served(top_hz, rate_hz):
        return
    lo, hi = check_band_hz(band_hz)
    nyquist = float(rate_hz) / 2.0
    raise BandNotServedError(
        f"the model's vibration band {fmt_number(lo)}-{fmt_number(hi)} Hz reaches {fmt_number(top_hz)} Hz, above the "
        f"Nyquist frequency {fmt_number(nyquist)} Hz of {where} (IMU at {fmt_number(rate_hz)} Hz); use a model trained "
        f"on a band below {fmt_number(nyquist)} Hz (retrain it with a band_hz LO HI below it)", parameter="band_hz"
    )
