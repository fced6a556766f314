"""A current model of a kind trained on logs and reported: what it was fitted on, its interval, its file."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import json_finite, save_figure
from terrawatt_base.checks import check_bool, check_choice, check_instance, check_int, check_real, check_seed
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import result_document
from terrawatt_base.plot_target import check_ax, check_plot_target, new_figure

from ..features.band import check_band_hz
from ..logs import InteractionLog, ground_name, run_names
from ..params import robot_params
from ..power import trapezoid
from .base import CurrentModel, TrainedOn, check_logs, log_currents
from .calibration import DEFAULT_INTERVAL_FOLDS, fit_interval
from .kinds import CURRENT_MODEL_KINDS, LEARNED_KINDS, new_current_model

__all__ = ["TRAINING_FORMAT_VERSION", "ModelOptions", "check_learned_band", "check_training_options", "RunCharge",
           "TrainingReport", "train_report"]

#: Layout of :meth:`TrainingReport.to_dict` (format ``terrawatt-training``).
TRAINING_FORMAT_VERSION = 1


def check_learned_band(band_hz: Sequence[float] | None, kinds: Sequence[str], *, name: str = "band_hz",
                       kinds_name: str = "kind") -> tuple[float, float] | None:
    """A checked vibration band for models of ``kinds`` (one must be learned), or None without one.

    Parameters
    ----------
    band_hz : pair of float or None
        ``(low_hz, high_hz)`` (:func:`energy.features.check_band_hz`).
    kinds : sequence of str
        The model kinds it is for.
    name, kinds_name : str
        The parameters the band and the kinds are (the error's :attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Returns
    -------
    (float, float) or None

    Raises
    ------
    InvalidParameterError
        A bad band; a band while none of ``kinds`` is in :data:`LEARNED_KINDS`.

    Examples
    --------
    >>> check_learned_band([0, 25], ["estimator", "linear"])
    (0.0, 25.0)
    """
    if band_hz is None:
        return None
    band = check_band_hz(band_hz, name)
    if not set(kinds) & set(LEARNED_KINDS):
        raise InvalidParameterError(f"{name} applies to the estimator and paper models only, got {kinds_name} "
                                    f"{' '.join(kinds)}", parameter=(name, kinds_name))
    return band


@dataclass(frozen=True)
class ModelOptions:
    """How a new current model of a kind is made (:func:`~energy.models.new_current_model`): one checked value.

    Parameters
    ----------
    seed : int or None
        Seed of the learned kinds.
    band_hz : pair of float, optional
        The learned kinds' vibration band (Hz, :func:`energy.features.check_band_hz`).
    robot : str, path or RobotParams, optional
        The physics kind's robot (:func:`energy.params.robot_params`; default husky).

    Raises
    ------
    InvalidParameterError
        A bad seed or band (the error names it: :attr:`~terrawatt_base.errors.TerrawattError.parameter`).
    UnknownNameError, FileFormatError
        A robot that is no preset nor robot file, or a robot file that does not read.

    Examples
    --------
    >>> ModelOptions(band_hz=[0, 25]).band_hz
    (0.0, 25.0)
    """

    seed: int | None = 0
    band_hz: tuple[float, float] | None = None
    robot: Any = None

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "seed", check_seed(self.seed))
        except InvalidParameterError as exc:
            raise InvalidParameterError(str(exc), parameter="seed") from None
        if self.band_hz is not None:
            object.__setattr__(self, "band_hz", check_band_hz(self.band_hz, "band_hz"))
        if self.robot is not None:
            robot_params(self.robot)

    def check_kinds(self, kinds: Sequence[str], *, kinds_name: str = "kinds") -> None:
        """Check that the options apply to ``kinds``: a band needs a learned kind, a robot the physics kind.

        Raises
        ------
        InvalidParameterError
            A band while none of ``kinds`` is learned, a robot while none is physics (the error names both
            parameters, ``kinds_name`` for the kinds).
        """
        check_learned_band(self.band_hz, kinds, kinds_name=kinds_name)
        if self.robot is not None and "physics" not in kinds:
            raise InvalidParameterError(f"robot applies to the physics model only, got {kinds_name} {' '.join(kinds)}",
                                        parameter=("robot", kinds_name))

    def new_model(self, kind: str, *, progress: bool = False, n_threads: int | None = None) -> CurrentModel:
        """A new unfitted model of ``kind`` with these options: the band for a learned kind, the robot for physics."""
        return new_current_model(kind, seed=self.seed, progress=progress, n_threads=n_threads,
                                 band_hz=self.band_hz if kind in LEARNED_KINDS else None,
                                 robot=self.robot if kind == "physics" else None)


def check_training_options(kind: str, *, n_threads: int | None = None, interval_folds: int = DEFAULT_INTERVAL_FOLDS,
                           options: ModelOptions | None = None) -> ModelOptions:
    """Check the options of :func:`train_report` before any work; return the model options (default ``ModelOptions()``).

    The errors name the options they are about (:attr:`~terrawatt_base.errors.TerrawattError.parameter`:
    a front end says them in its own words, e.g. the command line by its flags).

    Parameters
    ----------
    kind : str
        One of :data:`~energy.models.CURRENT_MODEL_KINDS`.
    n_threads : int, optional
        Torch threads while training: learned kinds only, >= 1.
    interval_folds : int
        0 (no interval) or >= 2.
    options : ModelOptions, optional
        The seed, the learned kinds' band, the physics kind's robot (:meth:`ModelOptions.check_kinds`).

    Returns
    -------
    ModelOptions

    Raises
    ------
    InvalidParameterError
        Threads not >= 1 or for a baseline; 1 or fewer than 0 interval folds; a band for a baseline; a robot
        for another kind than physics; options that are no ModelOptions.
    UnknownNameError
        ``kind`` is no model kind.

    Examples
    --------
    >>> check_training_options("linear", n_threads=2)
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: n_threads applies to the estimator and paper models only, got kind 'linear'
    """
    check_choice("kind", kind, CURRENT_MODEL_KINDS)
    options = ModelOptions() if options is None else check_instance("options", options, ModelOptions)
    if n_threads is not None:
        if isinstance(n_threads, bool) or not isinstance(n_threads, int) or n_threads < 1:
            raise InvalidParameterError(f"n_threads must be a positive number of threads, got {n_threads!r}",
                                        parameter="n_threads")
        if kind not in LEARNED_KINDS:
            raise InvalidParameterError(f"n_threads applies to the estimator and paper models only, got kind {kind!r}",
                                        parameter=("n_threads", "kind"))
    options.check_kinds([kind], kinds_name="kind")
    folds = check_int("interval_folds", interval_folds)
    if folds < 0 or folds == 1:
        raise InvalidParameterError(f"interval_folds must be 0 (no interval) or >= 2, got {folds}",
                                    parameter="interval_folds")
    return options


@dataclass(frozen=True)
class RunCharge:
    """One training run's total charge (both sides), measured and as the fitted model gives it back.

    Attributes
    ----------
    run : str
        The run's name (:func:`energy.logs.run_names`: ``<ground>/<file stem>``).
    ground : str
        Its ground label (``"unlabelled"`` without one).
    duration_s : float
        Its duration, s.
    measured_as, fitted_as : float
        Its logged and fitted charge, both sides together, A s.
    low_as, high_as : float
        The fitted model's central interval of that charge, A s (NaN for a model without an interval).
    """

    run: str
    ground: str
    duration_s: float
    measured_as: float
    fitted_as: float
    low_as: float
    high_as: float


@dataclass(frozen=True)
class TrainingReport:
    """A model of a kind fitted on logs, ready to save and to say what it is.

    Made by :func:`train_report`. :meth:`summary` is the line ``terrawatt train`` prints (the command
    adds the file it wrote), :meth:`to_dict` what the report knows as a versioned plain dict,
    :meth:`plot` the fit on the training runs, :meth:`write` saves the model to one file.

    Attributes
    ----------
    model : CurrentModel
        The fitted model.
    kind : str
        Its kind (:data:`~energy.models.CURRENT_MODEL_KINDS`).
    logs : tuple of InteractionLog
        The runs it was fitted on.
    fit_duration_s : float
        Wall time of the fit (and of the interval's refits), s.
    """

    model: CurrentModel
    kind: str
    logs: tuple[InteractionLog, ...]
    fit_duration_s: float

    @property
    def logs_duration_s(self) -> float:
        """Seconds of logs it was fitted on."""
        return float(sum(log.duration_s for log in self.logs))

    @property
    def band_hz(self) -> tuple[float, float] | None:
        """The learned model's vibration band (Hz), or None for a baseline."""
        band = getattr(getattr(self.model, "config_", None), "band_hz", None)
        return None if band is None else (float(band[0]), float(band[1]))

    def summary(self) -> str:
        """What was fitted on what, with or without a forecast interval, in how long (one line)."""
        band = self.band_hz
        band_text = f", vibration band {band[0]:g}-{band[1]:g} Hz" if band is not None else ""
        interval = "with a forecast interval" if self.model.gives_interval else "without a forecast interval"
        return (f"fitted {self.kind} on {len(self.logs)} runs ({self.logs_duration_s:.0f} s of logs{band_text}) "
                f"{interval} in {self.fit_duration_s:.1f} s")

    def to_dict(self) -> dict[str, Any]:
        """What the report knows, plain and JSON-ready (format ``terrawatt-training``).

        The kind and model class, the robots, seconds per ground, each run (name, ground,
        seconds), the seconds of logs, the fit time, the band, and the interval's facts: whether
        its residuals were cross-validated, the runs and grounds it was fitted on, the degrees of
        freedom on a new ground (``None``: Gaussian) and the per-sample correlation time
        (``"interval": None`` for a model without one). Nothing is predicted (see :meth:`run_charges`).
        """
        trained = TrainedOn.from_logs(self.logs)
        interval = getattr(self.model, "interval_", None)
        facts = None if interval is None else {
            "cross_validated": bool(interval.cross_validated), "n_runs": int(interval.n_runs),
            "n_grounds": int(interval.n_grounds), "new_ground_dof": interval.new_ground_dof,
            "correlation_s": float(interval.correlation_s)}
        return json_finite(result_document("training", TRAINING_FORMAT_VERSION, {
            "kind": self.kind, "model_class": type(self.model).__name__, "robots": list(trained.robots),
            "grounds_s": dict(trained.grounds),
            "runs": [{"run": name, "ground": ground_name(log), "duration_s": float(log.duration_s)}
                     for name, log in zip(run_names(self.logs), self.logs)],
            "n_runs": len(self.logs), "logs_duration_s": self.logs_duration_s, "fit_duration_s": self.fit_duration_s,
            "band_hz": self.band_hz, "gives_interval": self.model.gives_interval, "interval": facts}))

    def run_charges(self, level: float = 0.8) -> tuple[RunCharge, ...]:
        """Each training run's measured total charge against the fitted model's (in-sample: the model saw these runs).

        Parameters
        ----------
        level : float
            The central interval of the fitted charge (in (0, 1); NaN bounds without an interval).

        Returns
        -------
        tuple of RunCharge
        """
        level = check_real("level", level, low=0.0, high=1.0, low_inclusive=False, high_inclusive=False)
        out = []
        for name, log in zip(run_names(self.logs), self.logs):
            charge = self.model.predict_distribution(log).charge()
            low, high = charge.interval(level) if self.model.gives_interval else (math.nan, math.nan)
            measured = float(trapezoid(log_currents(log).sum(axis=1), log.time_s))
            out.append(RunCharge(name, ground_name(log), float(log.duration_s), measured, float(charge.total_mean_as),
                                 float(low), float(high)))
        return tuple(out)

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None, level: float = 0.8) -> Path | Any:
        """Fitted against measured total charge of each training run (mAh), one colour per ground, with the
        fitted model's ``level`` interval as bars (:meth:`run_charges`) and the line where they are equal.

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax`` (a matplotlib
        Axes to draw into; nothing is written and it is returned).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path``, ``ax`` or ``level``.
        """
        target = check_plot_target(path, ax)
        rows = self.run_charges(level)
        if target is None:
            axes = check_ax(ax)
        else:
            fig, axes = new_figure((5.0, 4.5))
        mah = 1000.0 / 3600.0
        for ground in sorted({r.ground for r in rows}):
            sel = [r for r in rows if r.ground == ground]
            x = np.array([r.measured_as for r in sel]) * mah
            y = np.array([r.fitted_as for r in sel]) * mah
            if self.model.gives_interval:
                err = np.array([[r.fitted_as - r.low_as for r in sel], [r.high_as - r.fitted_as for r in sel]]) * mah
                axes.errorbar(x, y, yerr=err, fmt="o", capsize=3, label=ground)
            else:
                axes.plot(x, y, "o", label=ground)
        ends = np.array([[r.measured_as, r.fitted_as, r.low_as, r.high_as] for r in rows]) * mah
        lo, hi = float(np.nanmin(ends)), float(np.nanmax(ends))
        pad = 0.05 * (hi - lo) if hi > lo else 1.0
        axes.plot([lo - pad, hi + pad], [lo - pad, hi + pad], color="0.5", lw=1, ls="--", label="fitted = measured")
        axes.set_xlabel("measured charge, both sides (mAh)")
        band = f", {100 * level:.0f} % interval" if self.model.gives_interval else ""
        axes.set_ylabel(f"fitted charge (mAh{band})")
        axes.set_title(f"{self.kind} on its {len(rows)} training runs (in-sample)")
        axes.legend(fontsize="small")
        if target is None:
            return axes
        fig.tight_layout()
        return save_figure(fig, target)

    def write(self, path: str | os.PathLike[str]) -> Path:
        """Save the model to ``path`` (one file, atomic: :meth:`CurrentModel.save`); return the path written."""
        return self.model.save(path)


def train_report(kind: str, logs: InteractionLog | Sequence[InteractionLog], *, options: ModelOptions | None = None,
                 progress: bool = False, n_threads: int | None = None,
                 interval_folds: int = DEFAULT_INTERVAL_FOLDS) -> TrainingReport:
    """A new model of ``kind`` (:func:`~energy.models.new_current_model`) fitted on ``logs``, and reported.

    A learned kind (:data:`LEARNED_KINDS`) is fitted as it is: its ensemble gives its own
    interval. Any other kind gets a cross-validated interval (:func:`~energy.models.fit_interval`
    with ``interval_folds`` folds) from two runs up, unless ``interval_folds`` is 0.

    Parameters
    ----------
    kind : str
        One of :data:`~energy.models.CURRENT_MODEL_KINDS`.
    logs : InteractionLog or sequence of InteractionLog
        Training runs with measured currents.
    options : ModelOptions, optional
        How the model is made: the seed of the learned kinds, their band, the physics kind's robot
        (default ``ModelOptions()``: seed 0, the kind's own band, husky).
    progress : bool
        The learned kinds' progress bar with the training loss (the baselines have none).
    n_threads, interval_folds
        As :func:`check_training_options`.

    Returns
    -------
    TrainingReport

    Raises
    ------
    InvalidParameterError, UnknownNameError
        As :func:`check_training_options`; no logs.
    TerrawattError
        As the model's ``fit`` and :func:`~energy.models.fit_interval`.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(50) * 0.1
    >>> log = InteractionLog(t, np.full(50, 0.5), np.zeros(50), np.full(50, 2.0), np.full(50, 2.1),
    ...                      np.arange(500) * 0.01, np.full(500, 9.81))
    >>> report = train_report("constant", log)
    >>> report.kind, len(report.logs), report.model.gives_interval
    ('constant', 1, False)
    """
    options = check_training_options(kind, n_threads=n_threads, interval_folds=interval_folds, options=options)
    learned = kind in LEARNED_KINDS
    progress = check_bool("progress", progress) and learned
    items = check_logs(logs)
    model = options.new_model(kind, progress=progress, n_threads=n_threads)
    t0 = time.perf_counter()
    if learned or interval_folds == 0 or len(items) < 2:
        model.fit(items)
    else:
        fit_interval(model, items, folds=interval_folds)
    return TrainingReport(model, kind, tuple(items), time.perf_counter() - t0)
