"""The vibration-conditioned current estimator, :class:`VibrationCurrentEstimator`.

The torch (CPU) estimator of "End-to-end current consumption estimation for a driving
system of a mobile robot considering geology", in three parts after minGPT: the model
(:mod:`~energy.models.net`), the windowed dataset (:mod:`~energy.models.data`) and the
training loop (:mod:`~energy.models.training`), configured by
:class:`~energy.models.config.EstimatorConfig`; this module holds the estimator that joins
them behind the :class:`~energy.models.base.CurrentModel`
contract. Every ensemble member is seeded through local ``torch.Generator`` objects (its
initial weights, dropout masks and shuffling); torch's global generator is never reseeded.

Sampling rates: the paper's 0.1 s windows of 10 samples assume drive streams at 100 Hz;
BorealTC's drive streams run at 6.5 Hz. Both presets resample explicitly with
:meth:`InteractionLog.resample` onto a uniform grid at ``rate_hz``: the ``"paper"`` preset
at 100 Hz (linear interpolation between drive samples — the 10-sample windows then hold
interpolated values, not measurements), the ``"default"`` preset at the training logs'
own median drive rate (no new samples are invented), with 1 s windows (6–7 samples at
6.5 Hz, stride one sample) and the local vibration spectrum of the 100 Hz IMU over each
window.

The ``"default"`` preset departs from the paper where leave-one-run-out on the BorealTC
logs said so: a physics prior (the physics model with rolling resistance, lateral friction
and idle current fitted to the training logs; the networks learn the residual), signed v
and omega (|omega| cannot tell the inner side of a turn), local spectra (12 bands over
``band_hz``, 1–12 Hz by default, over 1 s) instead of the whole-run spectrum (with few
training runs the 8000-bin — or even a 12-band — whole-run spectrum acts as a run
identifier the network memorises; held-out runs got worse), an ensemble of 5 members, dropout and weight decay,
early stopping on the tail of each run, and predictions clipped to the training current
range.

IMU rates: every spectrum is computed at its acceleration stream's own rate with bands
stated in Hz, so a model trained on 100 Hz logs predicts 50 Hz or 30 Hz logs as long as
its band (``EstimatorConfig.band_hz``) lies below their Nyquist frequency; a stream too
slow for the band is refused (:class:`~energy.features.BandNotServedError`, naming the
band, the rate and the fix) when fitting and when predicting.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import torch

from terrawatt_base.checks import check_bool, check_int, check_seed, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from ..features import (
    SOURCE_CURRENT_RANGE_A,
    SOURCE_OMEGA_RANGE_RADPS,
    SOURCE_SPEED_RANGE_MPS,
    MinMaxNormaliser,
    WindowSpec,
    band_rms_spectra,
    log_band_edges_hz,
    require_band,
    sliding_windows,
    whole_run_band_spectrum,
    whole_run_spectrum,
    window_starts,
    yaw_slip_features,
)
from ..logs import InteractionLog, rest_samples
from .base import CurrentModel, ModelRecord, log_currents, package_versions
from .baselines import PhysicsCurrentModel
from .config import EstimatorConfig, estimator_preset
from .data import WindowDataset
from .ensemble import train_ensemble
from .forecast import CurrentForecast
from .net import CurrentNet, CurrentNetConfig
from .training import TrainingHistory, train_network
from .uncertainty import IntervalModel

#: What the physics prior fits: the networks learn the residual, so the best fit matters, not which
#: constant current (idle or rolling resistance) carries it.
PRIOR_FIT_PARAMETERS = ("rolling_resistance_coef", "lateral_friction_coef", "idle_current_a", "rest_current_a")

__all__ = ["VibrationCurrentEstimator"]

_LOG_FLOOR_MPS2 = 1e-4  # floor of band RMS before log10 (m/s^2)
# ========================================================================= estimator
def _source_normaliser(source_range: tuple[float, float], absolute: bool) -> MinMaxNormaliser:
    """The source range for absolute values; mirrored (-high..high) for signed values."""
    if absolute:
        return MinMaxNormaliser(*source_range, absolute=True)
    return MinMaxNormaliser(-source_range[1], source_range[1], absolute=False)


def _root_seed(seed: int | None) -> int:
    """``seed``, or fresh entropy (one draw per fit) when it is None."""
    if seed is None:
        return int(np.random.SeedSequence().generate_state(1)[0])
    return int(seed)


def _member_seed(seed: int, member: int) -> int:
    return int(np.random.SeedSequence([int(seed), int(member)]).generate_state(1)[0])


class VibrationCurrentEstimator(CurrentModel):
    """Drive currents from velocity commands and the vertical vibration of the ground.

    Parameters
    ----------
    config : str or EstimatorConfig
        A preset name (``"default"``, ``"paper"``) or a configuration; change presets with
        ``estimator_preset("default").replace(n_members=3)``.
    seed : int
        Seed of weight initialisation, shuffling and dropout (members use derived seeds).
        The same seed, data and thread count give the same model.
    progress : bool
        Show a tqdm progress bar with the training and validation loss.
    n_threads : int or None
        ``torch.set_num_threads`` while fitting and predicting (restored after);
        ``None`` leaves torch's setting alone.

    Attributes
    ----------
    config_ : EstimatorConfig
        The resolved configuration.
    rate_hz_ : float
        Rate of the uniform grid the model works on (Hz).
    window_ : WindowSpec
        Training windows (length and stride in samples and seconds).
    band_edges_hz_ : numpy.ndarray or None
        Edges of the spectrum bands.
    normalisers_ : dict of str to MinMaxNormaliser
        ``"v"``, ``"omega"``, ``"current"`` (source ranges) and the fitted spectrum ranges
        (``"run"``, ``"local"`` when used).
    current_range_a_ : numpy.ndarray, shape (2, 2)
        ``[[min_left, min_right], [max_left, max_right]]`` of the training currents.
    networks_ : list of CurrentNet
        The ensemble members.
    history_ : tuple of TrainingHistory
        One per member.
    n_train_windows_ : int
    physics_ : PhysicsCurrentModel or None
        The fitted physics prior (``config.physics_prior``), or None.
    rest_current_a_ : numpy.ndarray, shape (2,), or None
        ``[left, right]`` current predicted where a log stands still
        (:func:`energy.logs.rest_samples`): the prior's rest level, or without a prior the
        mean of the training logs' rest samples; ``None`` (no rest sample in training and no
        prior, or a file from before the rest level): the networks predict rest too.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        est = VibrationCurrentEstimator("default", seed=0)
        est.fit(train_logs).predict(test_log)
    """

    _param_names = ("config", "seed", "progress", "n_threads")

    def __init__(self, config: str | EstimatorConfig = "default", seed: int = 0, progress: bool = False,
                 n_threads: int | None = None) -> None:
        self.config = config
        self.seed = seed
        self.progress = progress
        self.n_threads = n_threads

    # -------------------------------------------------------------- validation
    def _resolved_config(self) -> EstimatorConfig:
        if isinstance(self.config, EstimatorConfig):
            return self.config
        if isinstance(self.config, str):
            return estimator_preset(self.config)
        raise InvalidParameterError(f"config must be a preset name or an EstimatorConfig, got {self.config!r:.80}")

    def _check_params(self) -> EstimatorConfig:
        cfg = self._resolved_config()
        check_seed(self.seed)
        check_bool("progress", self.progress)
        if self.n_threads is not None:
            check_int("n_threads", self.n_threads, low=1)
        return cfg

    # ---------------------------------------------------------------- features
    def _grid_log(self, log: InteractionLog, rate_hz: float, method: str) -> InteractionLog:
        return log.resample(rate_hz, method)

    def _run_vector(self, log: InteractionLog, cfg: EstimatorConfig) -> np.ndarray:
        if cfg.run_features == "bins":
            return whole_run_spectrum(log.accel_time_s, log.accel_z_mps2, cfg.n_spectrum_bins,
                                      cfg.band_hz[1], cfg.spectrum_scaling)[1]
        if cfg.run_features == "bands":
            rms = whole_run_band_spectrum(log.accel_time_s, log.accel_z_mps2, cfg.spectrum_span_s, self.band_edges_hz_)
            return np.log10(np.maximum(rms, _LOG_FLOOR_MPS2))
        return np.zeros(0)

    def _window_features(self, grid: InteractionLog, spec: WindowSpec, starts: np.ndarray,
                         cfg: EstimatorConfig) -> tuple[np.ndarray, np.ndarray | None]:
        """Raw (unnormalised-spectrum) window features and local spectra of one gridded run."""
        nv, nw = self.normalisers_["v"], self.normalisers_["omega"]
        v = sliding_windows(nv.transform(grid.v_mps), spec, starts)
        w = sliding_windows(nw.transform(grid.omega_radps), spec, starts)
        motion = np.concatenate([v, w], axis=1)
        local = None
        if cfg.local_spectrum:
            t = grid.time_s
            centre = 0.5 * (t[starts] + t[starts + spec.length_samples - 1])
            rms = band_rms_spectra(grid.accel_time_s, grid.accel_z_mps2, centre, cfg.spectrum_span_s, self.band_edges_hz_)
            local = np.log10(np.maximum(rms, _LOG_FLOOR_MPS2))
        return motion, local

    def _yaw_slip(self, grid: InteractionLog, spec: WindowSpec, starts: np.ndarray) -> np.ndarray:
        if grid.gyro_z_radps is None:
            raise DataError(
                f"{grid.meta.source}: use_yaw_slip needs the gyro's yaw rate (InteractionLog.gyro_z_radps: "
                f"BorealTC 'wz', a bag's IMU angular_velocity.z); give logs with it or set use_yaw_slip=False"
            )
        return yaw_slip_features(grid.time_s, grid.omega_radps, grid.accel_time_s, grid.gyro_z_radps, spec, starts)

    def _feature_top_hz(self, cfg: EstimatorConfig) -> float:
        """The highest frequency the vibration features use (Hz; 0 without any)."""
        top = 0.0
        if self.band_edges_hz_ is not None:  # the top edge is exclusive: the last bin below it
            res = 1.0 / cfg.spectrum_span_s
            top = (math.ceil(float(self.band_edges_hz_[-1]) / res - 1e-6) - 1) * res
        if cfg.run_features == "bins":
            top = max(top, cfg.band_hz[1])
        return top

    def _targets(self, grid: InteractionLog, spec: WindowSpec, starts: np.ndarray) -> np.ndarray:
        cur = self.normalisers_["current"].transform(log_currents(grid))  # (N, 2)
        win = sliding_windows(cur, spec, starts)  # (n, W, 2)
        return np.concatenate([win[:, :, 0], win[:, :, 1]], axis=1)  # left window, right window

    def _dataset(self, grids: list[InteractionLog], spec: WindowSpec, cfg: EstimatorConfig,
                 with_targets: bool) -> WindowDataset:
        xs, idx, starts_all, ys, locals_, runs, yaws = [], [], [], [], [], [], []
        top_hz = self._feature_top_hz(cfg)
        for r, g in enumerate(grids):
            if top_hz > 0:
                require_band(cfg.band_hz, top_hz, g.accel_rate_hz, f"the acceleration stream of {g.meta.source!r}")
            starts = window_starts(len(g), spec)
            motion, local = self._window_features(g, spec, starts, cfg)
            xs.append(motion)
            if local is not None:
                locals_.append(local)
            if cfg.use_yaw_slip:
                yaws.append(self._yaw_slip(g, spec, starts))
            idx.append(np.full(starts.size, r))
            starts_all.append(starts)
            runs.append(self._run_vector(g, cfg))
            if with_targets:
                ys.append(self._targets(g, spec, starts))
        x = np.concatenate(xs)
        if locals_:
            if "local" not in self.normalisers_:
                self.normalisers_["local"] = MinMaxNormaliser.from_data(np.concatenate(locals_), per_column=True)
            x = np.concatenate([x, self.normalisers_["local"].transform(np.concatenate(locals_))], axis=1)
        if yaws:
            if "yaw" not in self.normalisers_:
                self.normalisers_["yaw"] = MinMaxNormaliser.from_data(np.concatenate(yaws), per_column=True)
            x = np.concatenate([x, self.normalisers_["yaw"].transform(np.concatenate(yaws))], axis=1)
        table = np.stack(runs)
        if table.shape[1]:
            if "run" not in self.normalisers_:
                # one range over all bins/bands: per-column ranges over a handful of runs
                # would blow run-to-run noise up to the full [0, 1] span
                self.normalisers_["run"] = MinMaxNormaliser.from_data(table, per_column=False)
            table = self.normalisers_["run"].transform(table)
        y = np.concatenate(ys) if with_targets else None
        return WindowDataset(x, table, np.concatenate(idx), np.concatenate(starts_all), spec, y)

    # ------------------------------------------------------------------- fit
    def _fit(self, logs: list[InteractionLog]) -> None:
        cfg = self._check_params()
        raw_logs = list(logs)
        with _threads(self.n_threads):
            cur = np.concatenate([log_currents(lg) for lg in logs])
            if cfg.absolute_currents:
                cur = np.abs(cur)
            self.current_range_a_ = np.stack([cur.min(axis=0), cur.max(axis=0)])
            self.physics_ = None
            if cfg.physics_prior is not None:
                prior = PhysicsCurrentModel(robot=cfg.physics_prior, fit_parameters=PRIOR_FIT_PARAMETERS)
                self.physics_ = prior.fit(logs)
                logs = [self._residual_log(lg) for lg in logs]
            rate = cfg.rate_hz if cfg.rate_hz is not None else float(np.median([lg.drive_rate_hz for lg in logs]))
            grids = [self._grid_log(lg, rate, cfg.resample_method) for lg in logs]
            spec = WindowSpec.from_seconds(cfg.window_s, rate, cfg.train_stride_s)
            self.config_ = cfg
            self.rate_hz_ = rate
            self.window_ = spec
            self.band_edges_hz_ = None
            if cfg.local_spectrum or cfg.run_features == "bands":
                acc_rate = float(np.median([g.accel_rate_hz for g in grids]))
                res = acc_rate / int(round(cfg.spectrum_span_s * acc_rate))
                lo, hi = cfg.band_hz
                self.band_edges_hz_ = log_band_edges_hz(cfg.n_bands, max(lo, res), hi, res)
            self.normalisers_ = {
                "v": _source_normaliser(SOURCE_SPEED_RANGE_MPS, cfg.absolute_inputs),
                "omega": _source_normaliser(SOURCE_OMEGA_RANGE_RADPS, cfg.absolute_inputs),
                "current": MinMaxNormaliser(*SOURCE_CURRENT_RANGE_A, absolute=cfg.absolute_currents),
            }
            data = self._dataset(grids, spec, cfg, with_targets=True)
            train, val = data.split_tail(cfg.validation_fraction)
            if cfg.patience is not None and val is None:
                raise DataError(
                    f"the training logs are too short for a {cfg.validation_fraction:g} validation tail of "
                    f"{spec.length_s:.3g} s windows; give longer logs or set patience=None"
                )
            net_cfg = cfg.net_config(data.x_window.shape[1], data.run_table.shape[1], data.y.shape[1])
            root = _root_seed(self.seed)
            seeds = [_member_seed(root, m) for m in range(cfg.n_members)]
            networks = [CurrentNet(net_cfg, seed=s) for s in seeds]
            folds = _member_folds(len(grids), cfg.n_members) if cfg.member_folds else None
            if len(networks) == 1:
                histories = [train_network(networks[0], train, val, cfg.train_config(), seeds[0], self.progress,
                                           f"{cfg.name} member 1/1")]
            else:  # the members in lockstep, one batched step for all (same weights as one after another)
                histories = train_ensemble(networks, train, val, cfg.train_config(), seeds, self.progress,
                                           f"{cfg.name} {cfg.n_members} members", folds)
            self.networks_ = networks
            self.history_ = tuple(histories)
            self.n_train_windows_ = len(train)
            self.rest_current_a_ = self._rest_level(raw_logs)
            self.ground_vibration_ = _ground_vibration(raw_logs)
            self.member_folds_ = None if folds is None or len(networks) == 1 else folds
            if self.member_folds_ is not None:  # out-of-fold residuals at no extra training
                self.interval_ = self._fit_interval(raw_logs, cfg)

    def _fit_interval(self, logs: list[InteractionLog], cfg: EstimatorConfig) -> IntervalModel:
        """The spreads of the forecast from out-of-fold residuals (and the prior's leave-one-ground-out residuals)."""
        folds = self.member_folds_
        residuals, predictions = [], []
        for r, lg in enumerate(logs):
            members = None if folds is None else [m for m in range(len(self.networks_)) if folds[r] == m]
            predictions.append(self._predict_with(lg, members or None))
            residuals.append(log_currents(lg) - predictions[-1])
        by_ground: dict[str, list[tuple[InteractionLog, np.ndarray, np.ndarray]]] = {}
        grounds = list(dict.fromkeys(str(lg.meta.ground_label) for lg in logs if lg.meta.ground_label is not None))
        if cfg.physics_prior is not None and len(grounds) >= 2:
            for g in grounds:
                others = [lg for lg in logs if str(lg.meta.ground_label) != g]
                prior = PhysicsCurrentModel(robot=cfg.physics_prior, fit_parameters=PRIOR_FIT_PARAMETERS).fit(others)
                pairs = [(lg, prior.predict(lg)) for lg in logs if str(lg.meta.ground_label) == g]
                by_ground[g] = [(lg, log_currents(lg) - p, p) for lg, p in pairs]
        return IntervalModel.fit(logs, residuals, predictions, cross_validated=folds is not None,
                                 new_ground_residuals=by_ground)

    def _rest_level(self, logs: list[InteractionLog]) -> np.ndarray | None:
        """Standing still is its own level, not the networks' business: the prior's, else the training mean."""
        if self.physics_ is not None:
            return np.asarray(self.physics_.rest_current_a_, dtype=np.float64).copy()
        rest = np.concatenate([log_currents(lg)[rest_samples(lg)] for lg in logs])
        if self.config_.absolute_currents:
            rest = np.abs(rest)
        return rest.mean(axis=0) if rest.shape[0] else None

    def _residual_log(self, log: InteractionLog) -> InteractionLog:
        prior = self.physics_.predict(log)
        return dataclasses.replace(log, current_left_a=log.current_left_a - prior[:, 0],
                                   current_right_a=log.current_right_a - prior[:, 1])

    # --------------------------------------------------------------- predict
    def _member_grid(self, grid: InteractionLog, members: list[int] | None) -> np.ndarray:
        """Each member's network output on the grid, shape (members, len(grid), 2)."""
        cfg = self.config_
        spec = WindowSpec.from_seconds(cfg.window_s, self.rate_hz_, cfg.predict_stride_s)
        data = self._dataset([grid], spec, cfg, with_targets=False)
        nets = self.networks_ if members is None else [self.networks_[m] for m in members]
        w = spec.length_samples
        rows = (data.start[:, None] + np.arange(w)[None, :]).reshape(-1)
        count = np.zeros(len(grid))
        np.add.at(count, rows, 1.0)
        out = np.empty((len(nets), len(grid), 2))
        with torch.no_grad():
            for i, net in enumerate(nets):
                y = self.normalisers_["current"].inverse_transform(net(*data.inputs(slice(None))).numpy().astype(np.float64))
                per_window = np.stack([y[:, :w], y[:, w:]], axis=2)  # (n, W, 2)
                total = np.zeros((len(grid), 2))
                np.add.at(total, rows, per_window.reshape(-1, 2))
                out[i] = total / count[:, None]
        return out

    def _on_log(self, log: InteractionLog, grid: InteractionLog, pred: np.ndarray) -> np.ndarray:
        """Grid currents back on the log's own timestamps, prior added, clipped, rest level set."""
        # drive samples outside the overlap of the drive and acceleration streams take the
        # nearest grid value (np.interp holds ends)
        out = np.column_stack([np.interp(log.time_s, grid.time_s, pred[:, k]) for k in range(2)])
        if self.physics_ is not None:
            out = out + self.physics_.predict(log)
        if self.config_.clip_output:
            out = np.clip(out, self.current_range_a_[0], self.current_range_a_[1])
        if self.rest_current_a_ is not None:
            out[rest_samples(log)] = self.rest_current_a_
        return out

    def _predict_with(self, log: InteractionLog, members: list[int] | None) -> np.ndarray:
        with _threads(self.n_threads):
            grid = self._grid_log(log, self.rate_hz_, self.config_.resample_method)
            pred = self._member_grid(grid, members).mean(axis=0)
        return self._on_log(log, grid, pred)

    def _predict(self, log: InteractionLog) -> np.ndarray:
        return self._predict_with(log, None)

    @property
    def uses_vibration(self) -> bool:
        """Whether the configuration reads the acceleration stream (local or whole-run spectra)."""
        cfg = self._resolved_config()
        return bool(cfg.local_spectrum or cfg.run_features != "none")

    def _predict_distribution(self, log: InteractionLog) -> CurrentForecast:
        """The mean and the members' disagreement from one pass of the members (0 standing still), with the interval."""
        with _threads(self.n_threads):
            grid = self._grid_log(log, self.rate_hz_, self.config_.resample_method)
            members = self._member_grid(grid, None)
        mean = self._on_log(log, grid, members.mean(axis=0))
        if getattr(self, "interval_", None) is None:
            return self._with_interval(log, mean)
        spread = np.column_stack([np.interp(log.time_s, grid.time_s, members[:, :, k].std(axis=0)) for k in range(2)])
        spread[rest_samples(log)] = 0.0
        return self._with_interval(log, mean, spread)

    def predict(self, log: InteractionLog) -> np.ndarray:
        """Predicted drive currents at the log's drive timestamps.

        The drive stream is resampled onto the model's uniform grid (``rate_hz_``) over the
        overlap of the drive and acceleration streams, predicted there window by window
        (overlapping windows averaged per sample) and interpolated linearly back onto
        ``log.time_s``. Drive samples outside that grid — before the acceleration stream
        starts, after it ends, or after the last grid time — take the nearest grid
        prediction (the ends are held, not extrapolated). The physics prior, when
        configured, is then added at ``log.time_s``, and ``clip_output`` clips the result
        to ``current_range_a_``. Samples that stand still take ``rest_current_a_``.

        Parameters, returns and errors as :meth:`CurrentModel.predict`; the ``DataError``
        here means the streams do not overlap, or overlap for less than one window.
        """
        return super().predict(log)

    # ------------------------------------------------------------ persistence
    def _params_to_plain(self) -> dict[str, Any]:
        p = self.get_params()
        p["config"] = self.config if isinstance(self.config, str) else {"__config__": self.config.to_dict()}
        return p

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        p = dict(params)
        if isinstance(p.get("config"), dict):
            p["config"] = EstimatorConfig.from_dict(p["config"]["__config__"])
        return p

    def _state(self) -> dict[str, Any]:
        return {
            "config": self.config_.to_dict(),
            "rate_hz": self.rate_hz_,
            "window": {"length_samples": self.window_.length_samples, "stride_samples": self.window_.stride_samples,
                       "rate_hz": self.window_.rate_hz},
            "band_edges_hz": self.band_edges_hz_,
            "normalisers": {k: v.to_dict() for k, v in self.normalisers_.items()},
            "current_range_a": np.asarray(self.current_range_a_),
            "net_config": dataclasses.asdict(self.networks_[0].config) | {"hidden_sizes": list(self.networks_[0].config.hidden_sizes)},
            "weights": [{k: v.detach().numpy().copy() for k, v in net.state_dict().items()} for net in self.networks_],
            "history": [h.to_dict() for h in self.history_],
            "n_train_windows": self.n_train_windows_,
            "physics": None if self.physics_ is None else _record_to_plain(self.physics_.to_record()),
            "rest_current_a": None if self.rest_current_a_ is None else self.rest_current_a_.tolist(),
            "ground_vibration": {g: {"time_s": t, "accel_z_mps2": a} for g, (t, a) in self.ground_vibration_.items()},
            "member_folds": None if self.member_folds_ is None else np.asarray(self.member_folds_),
        }

    def _load_state(self, state: dict[str, Any]) -> None:
        self.config_ = EstimatorConfig.from_dict(state["config"])
        self.rate_hz_ = float(state["rate_hz"])
        self.window_ = WindowSpec(**state["window"])
        edges = state["band_edges_hz"]
        self.band_edges_hz_ = None if edges is None else real_array("band_edges_hz", edges, ndim=1)
        if self.band_edges_hz_ is not None and "band_hz" not in state["config"]:
            self.band_edges_hz_ = _legacy_band_edges(self.band_edges_hz_, self.config_.spectrum_span_s)
        self.normalisers_ = {str(k): MinMaxNormaliser.from_dict(v) for k, v in state["normalisers"].items()}
        needed = {"v", "omega", "current"} | ({"local"} if self.config_.local_spectrum else set())
        needed |= {"yaw"} if self.config_.use_yaw_slip else set()
        needed |= {"run"} if self.config_.run_features != "none" else set()
        if needed - set(self.normalisers_):
            raise KeyError(f"normalisers {sorted(needed - set(self.normalisers_))!r} are missing")
        self.current_range_a_ = real_array("current_range_a", state["current_range_a"]).reshape(2, 2)
        nc = dict(state["net_config"])
        nc["hidden_sizes"] = tuple(nc["hidden_sizes"])
        net_cfg = CurrentNetConfig(**nc)
        nets = []
        for weights in state["weights"]:
            for name, value in weights.items():
                if not np.all(np.isfinite(np.asarray(value, dtype=np.float64))):
                    raise ValueError(f"network weight {name!r} holds non-finite values")
            net = CurrentNet(net_cfg, seed=0)  # every weight is replaced below
            net.load_state_dict({str(k): torch.from_numpy(np.asarray(v, dtype=np.float32)) for k, v in weights.items()})
            net.eval()
            nets.append(net)
        if not nets:
            raise ValueError("no ensemble member weights")
        self.networks_ = nets
        self.history_ = tuple(TrainingHistory.from_dict(h) for h in state["history"])
        self.n_train_windows_ = int(state["n_train_windows"])
        self.physics_ = None
        if state["physics"] is not None:
            prior = state["physics"]
            record = ModelRecord(str(prior.get("model_class", "PhysicsCurrentModel")), prior["params"], prior["state"])
            self.physics_ = PhysicsCurrentModel.from_record(record, "the estimator's physics prior")
        rest = state.get("rest_current_a")  # absent in files from before the rest level: the networks predict rest
        self.rest_current_a_ = None if rest is None else real_array("rest_current_a", rest).reshape(2)
        vib = state.get("ground_vibration") or {}  # absent in files from before it was recorded
        self.ground_vibration_ = {
            str(g): (real_array("ground_vibration time_s", v["time_s"], ndim=1),
                     real_array("ground_vibration accel_z_mps2", v["accel_z_mps2"], ndim=1))
            for g, v in dict(vib).items()
        }
        for g, (t, a) in self.ground_vibration_.items():
            if t.shape != a.shape or t.size < 2 or np.any(np.diff(t) <= 0):
                raise ValueError(f"the recorded vibration of ground {g!r} is not an increasing time series")
        folds = state.get("member_folds")  # absent in files from before the cross-validation ensemble
        if folds is not None:
            folds = np.asarray(folds)
            if folds.ndim != 1 or folds.dtype.kind not in "iu" or np.any((folds < 0) | (folds >= len(nets))):
                raise ValueError(f"member_folds must be a list of member indices below {len(nets)}")
            folds = folds.astype(np.int64)
        self.member_folds_ = folds

    def ground_vibration(self, ground: str) -> tuple[np.ndarray, np.ndarray] | None:
        """The vertical acceleration of ``ground`` kept from training (the longest run's first seconds), or None.

        Ground names match case-insensitively.
        """
        self._check_fitted()
        key = str(ground).lower()
        for g, (t, a) in self.ground_vibration_.items():
            if g.lower() == key:
                return t.copy(), a.copy()
        return None

    def _versions(self) -> dict[str, str]:
        return package_versions(torch=str(torch.__version__))


#: Seconds of vertical acceleration kept per training ground (:meth:`VibrationCurrentEstimator.ground_vibration`).
GROUND_VIBRATION_S = 30.0


def _member_folds(n_runs: int, n_members: int) -> np.ndarray | None:
    """Fold (= the member that never sees it) of every training run: ``run % n_members``; None below 2 runs."""
    if n_runs < 2 or n_members < 2:
        return None
    return np.arange(n_runs) % n_members


def _ground_vibration(logs: list[InteractionLog]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per labelled ground: the first :data:`GROUND_VIBRATION_S` seconds of its longest run's acceleration stream."""
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for g in dict.fromkeys(str(lg.meta.ground_label) for lg in logs if lg.meta.ground_label is not None):
        run = max((lg for lg in logs if str(lg.meta.ground_label) == g), key=lambda lg: lg.duration_s)
        t = np.asarray(run.accel_time_s, dtype=np.float64)
        keep = t <= t[0] + GROUND_VIBRATION_S
        out[g] = (t[keep] - t[0], np.asarray(run.accel_z_mps2, dtype=np.float64)[keep])
    return out


def _legacy_band_edges(edges_hz: np.ndarray, span_s: float) -> np.ndarray:
    """Band edges saved before ``band_hz`` existed, moved half an FFT bin so that every band
    keeps the bins it had: those releases put a bin lying on an edge into the band below it
    and left the bins on the lowest and the top edge out."""
    half = 0.5 / span_s
    out = edges_hz + half
    out[-1] = edges_hz[-1] - half
    return out


def _record_to_plain(record: ModelRecord) -> dict[str, Any]:
    return {"model_class": record.model_class, "params": record.params, "state": record.state}


class _threads:
    """Context manager: ``torch.set_num_threads(n)`` inside, previous value restored after."""

    def __init__(self, n: int | None) -> None:
        self.n = n
        self.old: int | None = None

    def __enter__(self) -> None:
        if self.n is not None:
            self.old = torch.get_num_threads()
            torch.set_num_threads(int(self.n))

    def __exit__(self, *exc: Any) -> None:
        if self.old is not None:
            torch.set_num_threads(self.old)
