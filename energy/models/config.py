"""Everything that defines a vibration-conditioned estimator: :class:`EstimatorConfig` and its named presets."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from terrawatt_base.checks import check_bool, check_choice, check_int, check_real, check_text
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from ..features import DEFAULT_BAND_HZ, DEFAULT_T_INTERVAL_S, SPECTRUM_SCALINGS, check_band_hz
from ..logs import RESAMPLE_METHODS
from ..params import ROBOT_PRESETS
from .net import CurrentNetConfig
from .training import TrainConfig

__all__ = [
    "RUN_FEATURES",
    "RESAMPLE_METHODS",
    "EstimatorConfig",
    "ESTIMATOR_PRESETS",
    "estimator_preset",
]

#: Whole-run vibration features of :class:`EstimatorConfig`.
RUN_FEATURES = ("bins", "bands", "none")


@dataclass(frozen=True)
class EstimatorConfig:
    """Everything that defines a :class:`VibrationCurrentEstimator`: features, network, training.

    The field defaults are the ``"default"`` preset; ``ESTIMATOR_PRESETS["paper"]`` sets
    every field the paper fixes.

    Parameters
    ----------
    name : str
        Label (presets use their key).
    rate_hz : float or None
        Rate (Hz) of the uniform grid the drive stream is resampled onto; ``None`` takes
        the median drive rate of the training logs (no invented samples).
    resample_method : {"linear", "previous"}
        Interpolation of :meth:`InteractionLog.resample`.
    window_s : float
        ``t_interval``: window length (s); samples = ``round(window_s * rate)``, >= 1.
    train_stride_s, predict_stride_s : float or None
        Stride between windows when training / predicting (s, rounded to >= 1 sample);
        ``None`` = ``window_s`` (tiling windows, as in the paper). Overlapping predicted
        windows are averaged per sample.
    absolute_inputs : bool
        Feed |v| and |omega| (the paper) instead of signed values (which tell the left
        side from the right in turns).
    absolute_currents : bool
        Learn |current| (the paper) instead of the signed current.
    run_features : {"bins", "bands", "none"}
        Whole-run vibration features: the paper's FFT spectrum on ``n_spectrum_bins`` bins
        (``"bins"``), the log10 band RMS averaged over the run (``"bands"``), or nothing;
        both min-max scaled by one range over all bins/bands of the training runs.
    n_spectrum_bins : int
        Bins of the ``"bins"`` spectrum (paper: 8000).
    spectrum_scaling : {"amplitude", "density"}
        Scaling of the ``"bins"`` spectrum (see :func:`~energy.features.whole_run_spectrum`).
    band_hz : (float, float)
        ``(low_hz, high_hz)``, the frequency band of every vibration feature, ``0 <= low <
        high``: the local spectra and the ``"bands"`` run features split it into
        ``n_bands`` log-spaced bands (``low == 0`` starts at the first non-zero bin); the
        ``"bins"`` spectrum spans 0 to ``high_hz`` (the paper: 50 Hz). The default,
        :data:`~energy.features.DEFAULT_BAND_HZ` (1-12 Hz), is served by every IMU of
        25 Hz or more; a model predicts from any stream whose Nyquist frequency reaches
        its band and refuses the others.
    local_spectrum : bool
        Add each window's local spectrum: log10 band RMS of the vertical acceleration over
        ``spectrum_span_s`` seconds centred on the window.
    spectrum_span_s : float
        Segment length of local spectra and of the ``"bands"`` Welch average (s).
    n_bands : int
        Log-spaced bands in ``band_hz`` (each at least one ``1 / spectrum_span_s`` bin wide).
    use_yaw_slip : bool
        Add each window's yaw-rate slip (:func:`~energy.features.yaw_slip_features`: the
        gyro's yaw rate against the wheel-derived omega), min-max scaled on the training
        windows; every log then needs a gyro stream (``InteractionLog.gyro_z_radps``).
    hidden_sizes : tuple of int
        Hidden layer widths (paper: 3 x 100).
    dropout : float
        Dropout after each hidden layer.
    n_members : int
        Ensemble size; members differ in seed, predictions are averaged.
    member_folds : bool
        A cross-validation ensemble: member ``m`` never trains on the runs whose index (in
        the order given) is ``m`` modulo ``n_members``, so every training run has an
        out-of-fold prediction — the residuals the forecast interval is fitted on
        (:class:`~energy.models.uncertainty.IntervalModel`). Needs 2 training runs or more
        (with fewer, every member sees everything and the interval is in-sample, marked so).
    max_epochs, batch_size, learning_rate, weight_decay, patience, loss
        Training settings (see :class:`TrainConfig`).
    validation_fraction : float
        Tail fraction of every training run held out for validation, in [0, 0.5]; > 0
        when ``patience`` is set. Without early stopping (``patience=None``) the tail is
        only scored (``TrainingHistory.validation_loss``), never trained on: 0 trains on
        every window (the ``"paper"`` preset).
    clip_output : bool
        Clip predictions to the per-side range of the training currents (stored with the
        model as ``current_range_a_``).
    physics_prior : str or None
        Robot preset name (:data:`~energy.params.ROBOT_PRESETS`) of a physics prior: a
        :class:`~energy.models.baselines.PhysicsCurrentModel` is fitted to the training logs
        first (rolling resistance, lateral friction, idle current) and the networks learn
        the residual current on top of it. ``None`` learns the currents directly (the
        paper).
    """

    name: str = "custom"
    rate_hz: float | None = None
    resample_method: str = "linear"
    window_s: float = 1.0
    train_stride_s: float | None = 0.1
    predict_stride_s: float | None = 0.1
    absolute_inputs: bool = False
    absolute_currents: bool = False
    run_features: str = "none"
    n_spectrum_bins: int = 8000
    spectrum_scaling: str = "amplitude"
    band_hz: tuple[float, float] = DEFAULT_BAND_HZ
    local_spectrum: bool = True
    spectrum_span_s: float = 1.0
    n_bands: int = 12
    use_yaw_slip: bool = False
    hidden_sizes: tuple[int, ...] = (64, 64)
    dropout: float = 0.1
    n_members: int = 5
    member_folds: bool = True
    max_epochs: int = 60
    batch_size: int = 256
    learning_rate: float = 2e-3
    weight_decay: float = 1e-3
    patience: int | None = 10
    loss: str = "mse"
    validation_fraction: float = 0.15
    clip_output: bool = True
    physics_prior: str | None = "husky"

    def __post_init__(self) -> None:
        own = "EstimatorConfig"
        check_text("name", self.name, owner=own)
        if self.rate_hz is not None:
            check_real("rate_hz", self.rate_hz, low=0.0, low_inclusive=False, owner=own)
        check_choice(f"{own}.resample_method", self.resample_method, RESAMPLE_METHODS)
        object.__setattr__(self, "band_hz", check_band_hz(self.band_hz, f"{own}.band_hz"))
        for name in ("window_s", "spectrum_span_s"):
            check_real(name, getattr(self, name), low=0.0, low_inclusive=False, owner=own)
        for name in ("train_stride_s", "predict_stride_s"):
            if getattr(self, name) is not None:
                check_real(name, getattr(self, name), low=0.0, low_inclusive=False, owner=own)
        for name in ("absolute_inputs", "absolute_currents", "local_spectrum", "clip_output", "use_yaw_slip",
                     "member_folds"):
            check_bool(f"{own}.{name}", getattr(self, name))
        check_choice(f"{own}.run_features", self.run_features, RUN_FEATURES)
        check_choice(f"{own}.spectrum_scaling", self.spectrum_scaling, SPECTRUM_SCALINGS)
        for name in ("n_spectrum_bins", "n_bands", "n_members"):
            check_int(name, getattr(self, name), low=1, owner=own)
        if self.local_spectrum or self.run_features == "bands":
            self._check_bands_fit()
        check_real("validation_fraction", self.validation_fraction, low=0.0, high=0.5, owner=own)
        if self.physics_prior is not None and (not isinstance(self.physics_prior, str) or self.physics_prior not in ROBOT_PRESETS):
            raise UnknownNameError(
                f"EstimatorConfig.physics_prior must be None or a robot preset from {sorted(ROBOT_PRESETS)!r}, "
                f"got {self.physics_prior!r}"
            )
        if self.physics_prior is not None and self.absolute_currents:
            raise InvalidParameterError(
                "EstimatorConfig.absolute_currents cannot be combined with a physics_prior (the networks "
                "learn a signed residual); set physics_prior=None or absolute_currents=False"
            )
        if self.patience is not None and self.validation_fraction == 0:
            raise InvalidParameterError("EstimatorConfig.patience (early stopping) needs validation_fraction > 0")
        if isinstance(self.hidden_sizes, (str, bytes)) or not hasattr(self.hidden_sizes, "__iter__"):
            raise InvalidParameterError(f"EstimatorConfig.hidden_sizes must be a tuple of ints >= 1, got {self.hidden_sizes!r}")
        object.__setattr__(self, "hidden_sizes", tuple(self.hidden_sizes))
        self.net_config(1, 0, 1)  # validates hidden_sizes and dropout
        self.train_config()  # validates the training settings

    def _check_bands_fit(self) -> None:
        """``n_bands`` bands of at least one ``1 / spectrum_span_s`` bin fit in ``band_hz``."""
        res = 1.0 / self.spectrum_span_s
        first = max(int(round(self.band_hz[0] / res)), 1)
        top = int(math.floor(self.band_hz[1] / res + 1e-9)) + 1
        if first + self.n_bands > top:
            raise InvalidParameterError(
                f"EstimatorConfig.band_hz={self.band_hz!r} holds {max(top - first, 0)} frequency bin(s) of "
                f"{res:.4g} Hz (1 / spectrum_span_s), fewer than n_bands={self.n_bands!r}; widen the band "
                f"(`band_hz`), use fewer bands or a longer spectrum_span_s", parameter="band_hz"
            )

    def net_config(self, n_window_inputs: int, n_run_inputs: int, n_outputs: int) -> CurrentNetConfig:
        """The :class:`CurrentNetConfig` for given input/output sizes."""
        return CurrentNetConfig(n_window_inputs, n_run_inputs, n_outputs, self.hidden_sizes, self.dropout)

    def train_config(self) -> TrainConfig:
        """The :class:`TrainConfig` part."""
        return TrainConfig(self.max_epochs, self.batch_size, self.learning_rate, self.weight_decay,
                           self.patience, self.loss)

    def replace(self, **changes: Any) -> EstimatorConfig:
        """A copy with some fields changed (validated)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form (for checkpoints and JSON)."""
        d = dataclasses.asdict(self)
        d["hidden_sizes"] = list(self.hidden_sizes)
        d["band_hz"] = list(self.band_hz)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> EstimatorConfig:
        """Rebuild from :meth:`to_dict` output (unknown keys raise InvalidParameterError).

        Configurations saved before ``band_hz`` existed (``min_band_hz``, default 1, and
        ``max_frequency_hz``, default 50) are read as ``band_hz=(min_band_hz,
        max_frequency_hz)``.
        """
        d = dict(d)
        if "min_band_hz" in d or "max_frequency_hz" in d:
            if "band_hz" in d:
                raise InvalidParameterError("an EstimatorConfig has band_hz or the older min_band_hz/max_frequency_hz, not both")
            d["band_hz"] = (d.pop("min_band_hz", 1.0), d.pop("max_frequency_hz", 50.0))
        known = {f.name for f in dataclasses.fields(cls)}
        extra = set(d) - known
        if extra:
            raise InvalidParameterError(f"unknown EstimatorConfig field(s) {sorted(extra)!r}")
        if "hidden_sizes" in d:
            d["hidden_sizes"] = tuple(d["hidden_sizes"])
        return cls(**d)


#: Named configurations: ``"paper"`` reproduces the source network (8000-bin whole-run
#: spectrum + 10 |v| + 10 |omega| at 100 Hz -> 3 x 100 ReLU -> 10 + 10 currents, trained
#: on every window of the training runs; the paper does not state its optimiser, epochs or
#: batch size: Adam, 50 epochs, batch 256 here; its 0-50 Hz spectrum needs a 100 Hz IMU);
#: ``"default"`` is the improved estimator (see the module docstring).
ESTIMATOR_PRESETS: dict[str, EstimatorConfig] = {
    "paper": EstimatorConfig(
        name="paper", rate_hz=100.0, resample_method="linear", window_s=DEFAULT_T_INTERVAL_S,
        train_stride_s=None, predict_stride_s=None, absolute_inputs=True, absolute_currents=True,
        run_features="bins", n_spectrum_bins=8000, spectrum_scaling="amplitude", band_hz=(0.0, 50.0),
        local_spectrum=False, hidden_sizes=(100, 100, 100), dropout=0.0, n_members=1,
        max_epochs=50, batch_size=256, learning_rate=1e-3, weight_decay=0.0, patience=None,
        loss="mse", validation_fraction=0.0, clip_output=False, physics_prior=None,
    ),
    "default": EstimatorConfig(name="default"),
}


def estimator_preset(name: str) -> EstimatorConfig:
    """The :class:`EstimatorConfig` preset called ``name``.

    Raises
    ------
    UnknownNameError
        ``name`` is not a key of :data:`ESTIMATOR_PRESETS`.
    """
    try:
        return ESTIMATOR_PRESETS[name]
    except (KeyError, TypeError):
        raise UnknownNameError(f"estimator preset {name!r} is unknown; expected one of {sorted(ESTIMATOR_PRESETS)!r}") from None
