"""The drive-current model contract and its torch-free, versioned one-file persistence.

Everything that predicts the left and right drive currents of an :class:`InteractionLog`
derives from :class:`CurrentModel` (scikit-learn contract: the constructor stores its
arguments; ``fit(logs)`` validates, sets attributes ending in ``_`` and returns ``self``;
``predict(log)`` returns an ``(N, 2)`` array of ``[left, right]`` currents in A at
``log.time_s``; ``score`` is R²).

A fitted model is saved as one file (:meth:`CurrentModel.save`), written atomically
through :mod:`terrawatt_base.atomic`: a zip archive holding ``model.json`` (the format, its
version, the model class, the constructor parameters, the fitted state in plain types, the
package versions, what the model was trained on — :class:`TrainedOn` — and its
forecast interval, :class:`~energy.models.uncertainty.IntervalModel`; the last two are
optional, older files lack them) and one ``.npy`` entry per array of the state (numpy's
own format, read without pickle, sizes checked by :mod:`terrawatt_base.containers` before
anything is inflated). No torch is needed to write or read it: the estimator stores its
network weights as arrays like any other state. Files of format version 1 (``torch.save``
checkpoints of every model class) are still read; torch is imported only for them.

This module imports no model class; :func:`energy.models.load_current_model` dispatches a
file to its class by the stored class name.
"""

from __future__ import annotations

import importlib.metadata
import io
import json
import os
import platform
import zipfile
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from terrawatt_base.atomic import atomic_open, check_output_path, remove_stale_temporaries
from terrawatt_base.checks import check_int, check_real
from terrawatt_base.containers import check_zip_sizes, load_npy, read_zip_entry
from terrawatt_base.errors import (
    DataError,
    FileFormatError,
    FormatVersionError,
    InvalidParameterError,
    NotFittedError,
)

from ..logs import InteractionLog, ground_name
from .forecast import CurrentForecast
from .uncertainty import IntervalModel

__all__ = [
    "CURRENT_MODEL_FORMAT",
    "CURRENT_MODEL_FORMAT_VERSION",
    "LEGACY_FORMAT_VERSIONS",
    "CurrentModel",
    "ModelRecord",
    "TrainedOn",
    "check_logs",
    "log_currents",
    "package_versions",
    "read_model_file",
    "write_model_file",
]

#: ``format`` field of every current-model file.
CURRENT_MODEL_FORMAT = "terrawatt-current-model"
#: Version of the file layout written by this release (2: zip of JSON + ``.npy`` arrays).
CURRENT_MODEL_FORMAT_VERSION = 2
#: Older versions this release still reads (1: a ``torch.save`` checkpoint; needs torch).
LEGACY_FORMAT_VERSIONS = (1,)

_JSON_ENTRY = "model.json"
_ARRAY_KEY = "__array__"
_FAILURES = (KeyError, TypeError, ValueError, AttributeError, IndexError, RuntimeError, OverflowError, RecursionError)


def check_logs(logs: Any, name: str = "logs") -> list[InteractionLog]:
    """``logs`` (one InteractionLog or a non-empty sequence of them) as a list.

    Raises
    ------
    InvalidParameterError
        Anything else.
    """
    if isinstance(logs, InteractionLog):
        return [logs]
    if isinstance(logs, (str, bytes)) or not isinstance(logs, Sequence):
        raise InvalidParameterError(f"{name} must be an InteractionLog or a sequence of them, got {logs!r:.80}")
    items = list(logs)
    if not items:
        raise InvalidParameterError(f"{name} must hold at least one InteractionLog, got an empty sequence")
    for i, log in enumerate(items):
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"{name}[{i}] must be an InteractionLog, got {log!r:.80}")
    return items


def log_currents(log: InteractionLog) -> np.ndarray:
    """The logged ``[left, right]`` drive currents of ``log``, ``(N, 2)``, in A; DataError without any."""
    log.require_currents("training, adaptation, scoring or diagnosis")
    return np.column_stack([log.current_left_a, log.current_right_a])


def package_versions(**extra: str) -> dict[str, str]:
    """Versions of terrawatt, numpy and Python (plus ``extra``), as stored with a model."""
    try:
        own = importlib.metadata.version("terrawatt")
    except importlib.metadata.PackageNotFoundError:
        own = "unknown"
    return {"terrawatt": own, "numpy": str(np.__version__), "python": platform.python_version(), **extra}


@dataclass(frozen=True)
class ModelRecord:
    """The content of a current-model file: class name, parameters and fitted state.

    ``params`` and ``state`` hold plain types (dict, list, str, numbers, bool, None) and
    numpy arrays.
    """

    model_class: str
    params: dict[str, Any]
    state: dict[str, Any]
    versions: dict[str, Any] = field(default_factory=dict)
    format_version: int = CURRENT_MODEL_FORMAT_VERSION
    trained_on: dict[str, Any] | None = None
    interval: dict[str, Any] | None = None


@dataclass(frozen=True)
class TrainedOn:
    """What a model was fitted on: robots, grounds (seconds of driving each) and runs.

    Saved in the model file (``trained_on``) so that a planner can refuse a model of another
    robot or one that never drove a ground of the map; files without it read as ``None``.

    Attributes
    ----------
    robots : tuple of str
        ``meta.robot`` of the logs (``"unknown"`` where a log does not say).
    grounds : dict of str to float
        Seconds of driving per ``meta.ground_label`` (logs without a label under ``"unlabelled"``).
    runs : int
        Number of logs.
    """

    robots: tuple[str, ...]
    grounds: dict[str, float]
    runs: int

    @classmethod
    def from_logs(cls, logs: Sequence[InteractionLog]) -> TrainedOn:
        grounds: dict[str, float] = {}
        for lg in logs:
            key = ground_name(lg)
            grounds[key] = grounds.get(key, 0.0) + float(lg.duration_s)
        return cls(tuple(sorted({str(lg.meta.robot) for lg in logs})), grounds, len(logs))

    def merged(self, other: TrainedOn) -> TrainedOn:
        """Both summaries together (e.g. a model and the data it was adapted on)."""
        grounds = dict(self.grounds)
        for g, s in other.grounds.items():
            grounds[g] = grounds.get(g, 0.0) + s
        return TrainedOn(tuple(sorted(set(self.robots) | set(other.robots))), grounds, self.runs + other.runs)

    def to_plain(self) -> dict[str, Any]:
        return {"robots": list(self.robots), "grounds": dict(self.grounds), "runs": self.runs}

    @classmethod
    def from_plain(cls, value: Any) -> TrainedOn:
        """The summary of a file entry (:meth:`to_plain`).

        Raises
        ------
        InvalidParameterError
            A malformed entry: robots not a list of strings, grounds not a mapping of
            names to non-negative seconds, runs not a non-negative integer.
        """
        if not isinstance(value, Mapping) or set(value) != {"robots", "grounds", "runs"}:
            raise InvalidParameterError("the training summary must hold exactly 'robots', 'grounds' and 'runs'")
        robots, grounds = value["robots"], value["grounds"]
        if not isinstance(robots, list) or not all(isinstance(r, str) for r in robots):
            raise InvalidParameterError("the training summary's robots must be a list of names")
        if not isinstance(grounds, Mapping):
            raise InvalidParameterError("the training summary's grounds must map names to seconds")
        seconds = {str(k): check_real(f"seconds on {k!r}", v, low=0.0) for k, v in grounds.items()}
        return cls(tuple(robots), seconds, check_int("runs", value["runs"], low=0))


# ------------------------------------------------------------------ file format
def _encode(value: Any, arrays: list[np.ndarray]) -> Any:
    if isinstance(value, np.ndarray):
        arrays.append(value)
        return {_ARRAY_KEY: f"arrays/{len(arrays) - 1}.npy"}
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {str(k): _encode(v, arrays) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_encode(v, arrays) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"cannot store a {type(value).__name__} in a current-model file")


def _decode(value: Any, archive: zipfile.ZipFile, where: str) -> Any:
    if isinstance(value, dict):
        if set(value) == {_ARRAY_KEY}:
            ref = value[_ARRAY_KEY]
            if not isinstance(ref, str):
                raise TypeError(f"array reference {ref!r} is not an entry name")
            return load_npy(read_zip_entry(archive, ref, where), where, f"entry {ref!r}", kinds="iuf")
        return {k: _decode(v, archive, where) for k, v in value.items()}
    if isinstance(value, list):
        return [_decode(v, archive, where) for v in value]
    return value


def write_model_file(path: str | os.PathLike[str], record: ModelRecord) -> Path:
    """Write ``record`` to ``path`` atomically, in the current format; return the path.

    Raises
    ------
    InvalidParameterError
        ``path`` is a directory, or lies under a file.
    """
    target = check_output_path(path, "path")
    arrays: list[np.ndarray] = []
    header = {
        "format": CURRENT_MODEL_FORMAT,
        "format_version": CURRENT_MODEL_FORMAT_VERSION,
        "model_class": record.model_class,
        "params": _encode(record.params, arrays),
        "state": _encode(record.state, arrays),
        "versions": _encode(record.versions, arrays),
        "trained_on": _encode(record.trained_on, arrays),
        "interval": _encode(record.interval, arrays),
    }
    with atomic_open(target, "wb") as fh, zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr(_JSON_ENTRY, json.dumps(header, indent=1))
        for i, arr in enumerate(arrays):
            buf = io.BytesIO()
            np.save(buf, np.ascontiguousarray(arr), allow_pickle=False)
            archive.writestr(f"arrays/{i}.npy", buf.getvalue())
    return target


def _check_version(where: str, found: Any, expected: int) -> None:
    if found != expected:
        readable = sorted({CURRENT_MODEL_FORMAT_VERSION, *LEGACY_FORMAT_VERSIONS})
        raise FormatVersionError(
            f"{where} has current-model format version {found!r}; this release reads versions {readable} "
            f"(expected {expected} for this kind of file)"
        )


def _tensors_to_arrays(value: Any) -> Any:
    if type(value).__module__.startswith("torch") and hasattr(value, "numpy"):
        return value.detach().cpu().numpy()
    if isinstance(value, dict):
        return {str(k): _tensors_to_arrays(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_tensors_to_arrays(v) for v in value]
    return value


def _read_legacy(path: Path, where: str) -> dict[str, Any]:
    """A format-1 ``torch.save`` checkpoint as a plain dict (tensors become arrays)."""
    try:
        import torch  # only version-1 files need torch
    except ImportError as exc:  # pragma: no cover - torch is a dependency
        raise FormatVersionError(f"{where} is a version-1 (torch) current-model file; reading it needs torch") from exc
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # corrupt zip, truncated pickle, forbidden global...
        raise FileFormatError(f"{where} is not a readable terrawatt current-model file: {exc}") from exc
    if not isinstance(data, dict) or data.get("format") != CURRENT_MODEL_FORMAT:
        raise FileFormatError(f"{where} is not a terrawatt current-model file (no format {CURRENT_MODEL_FORMAT!r})")
    _check_version(where, data.get("format_version"), 1)
    return _tensors_to_arrays(data)


def read_model_file(path: str | os.PathLike[str]) -> ModelRecord:
    """Read a current-model file (this format, or a legacy version) into a :class:`ModelRecord`.

    Only the layout is checked here (format, version, entries and their types); whether
    the parameters and state make a model is checked by :meth:`CurrentModel.from_record`.

    Raises
    ------
    FileFormatError
        Missing, truncated, corrupt or foreign file; missing or mistyped entries.
    FormatVersionError
        A file of a format version this release cannot read (the message names the
        version found and the versions expected).
    """
    p = Path(path)
    where = repr(str(p))
    remove_stale_temporaries(p)
    if not p.is_file():
        raise FileFormatError(f"current-model file {where} does not exist or is not a file")
    try:
        with zipfile.ZipFile(p) as archive:
            check_zip_sizes(archive, where)  # before anything is inflated
            names = set(archive.namelist())
            if _JSON_ENTRY in names:
                data = json.loads(read_zip_entry(archive, _JSON_ENTRY, where).decode("utf-8"))
                if not isinstance(data, dict) or data.get("format") != CURRENT_MODEL_FORMAT:
                    raise FileFormatError(f"{where} is not a terrawatt current-model file (no format {CURRENT_MODEL_FORMAT!r})")
                _check_version(where, data.get("format_version"), CURRENT_MODEL_FORMAT_VERSION)
                data = {k: _decode(v, archive, where) for k, v in data.items()}
            elif any(n.endswith("/data.pkl") for n in names):
                data = None  # a torch checkpoint: format version 1
            else:
                raise FileFormatError(f"{where} is not a terrawatt current-model file (no {_JSON_ENTRY!r} entry)")
    except FileFormatError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError, OSError, UnicodeDecodeError, MemoryError,
            *_FAILURES) as exc:
        raise FileFormatError(f"{where} is not a readable terrawatt current-model file: {exc}") from exc
    if data is None:
        data = _read_legacy(p, where)
    for key, kind in (("model_class", str), ("params", dict), ("state", dict)):
        if key not in data:
            raise FileFormatError(f"{where} lacks the {key!r} entry of a current-model file")
        if not isinstance(data[key], kind):
            raise FileFormatError(f"{where}: the {key!r} entry must be a {kind.__name__}, got {type(data[key]).__name__}")
    versions = data.get("versions")
    trained_on = data.get("trained_on")
    interval = data.get("interval")
    for key, value in (("trained_on", trained_on), ("interval", interval)):
        if value is not None and not isinstance(value, dict):  # dropping it would silently change the model
            raise FileFormatError(f"{where}: the {key!r} entry must be a mapping or absent, got {type(value).__name__}")
    return ModelRecord(data["model_class"], data["params"], data["state"],
                       versions if isinstance(versions, dict) else {}, int(data["format_version"]),
                       trained_on if isinstance(trained_on, dict) else None,
                       interval if isinstance(interval, dict) else None)


# --------------------------------------------------------------------- contract
class CurrentModel:
    """Base of every drive-current model: fit on logs, predict ``[left, right]`` currents.

    Subclasses set ``_param_names`` (the constructor arguments), implement ``_fit``,
    ``_predict``, ``_state`` / ``_load_state`` and, for non-plain parameters,
    ``_params_to_plain`` / ``_params_from_plain``; ``_check_params`` validates the
    parameters (at ``fit`` and when loading). Every subclass is registered by class name
    (:meth:`registered`) so that files can name it.
    """

    _param_names: ClassVar[tuple[str, ...]] = ()
    _registry: ClassVar[dict[str, type[CurrentModel]]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        CurrentModel._registry[cls.__name__] = cls

    @staticmethod
    def registered(name: str) -> type[CurrentModel] | None:
        """The imported subclass called ``name``, or None."""
        return CurrentModel._registry.get(name) if isinstance(name, str) else None

    # -------------------------------------------------------------- parameters
    def get_params(self) -> dict[str, Any]:
        """The constructor arguments, by name."""
        return {name: getattr(self, name) for name in self._param_names}

    def clone(self) -> CurrentModel:
        """An unfitted model with the same parameters (scikit-learn's ``clone``)."""
        return type(self)(**self.get_params())

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"

    @property
    def is_fitted(self) -> bool:
        """Whether ``fit`` has run (some attribute ending in ``_`` is set)."""
        return any(k.endswith("_") and not k.startswith("_") for k in vars(self))

    def _check_fitted(self) -> None:
        if not self.is_fitted:
            raise NotFittedError(
                f"this {type(self).__name__} is not fitted yet; call fit(logs) before predict, score or save"
            )

    def _check_params(self) -> Any:
        """Validate the constructor arguments (raise InvalidParameterError / UnknownNameError)."""

    # ---------------------------------------------------------------- fit / predict
    def fit(self, logs: InteractionLog | Sequence[InteractionLog]) -> CurrentModel:
        """Fit the model to one or more interaction logs.

        Parameters
        ----------
        logs : InteractionLog or sequence of InteractionLog
            Training runs (each keeps its own time axis; runs are never joined across).

        Returns
        -------
        self

        Raises
        ------
        InvalidParameterError
            ``logs`` is not an InteractionLog or a non-empty sequence of them.
        DataError
            The logs are too short or otherwise unusable for this model.
        """
        items = check_logs(logs)
        self._clear_fitted()  # refit from scratch
        try:
            self._fit(items)
            self.trained_on_ = self._training_summary(items)
        except BaseException:
            self._clear_fitted()  # never leave a half-fitted model behind
            raise
        return self

    def _training_summary(self, logs: list[InteractionLog]) -> TrainedOn:
        """What :attr:`trained_on_` records for a fit on ``logs`` (a wrapper adds its base's)."""
        return TrainedOn.from_logs(logs)

    @property
    def training_summary(self) -> TrainedOn | None:
        """Robots, grounds and runs the model was fitted on (``None`` for a file saved before this was recorded)."""
        self._check_fitted()
        return getattr(self, "trained_on_", None)

    def _clear_fitted(self) -> None:
        for k in [k for k in vars(self) if k.endswith("_") and not k.startswith("_")]:
            delattr(self, k)

    def predict(self, log: InteractionLog) -> np.ndarray:
        """Predicted drive currents at the log's drive timestamps.

        Parameters
        ----------
        log : InteractionLog
            Uses ``time_s``, ``v_mps``, ``omega_radps`` (and the acceleration stream when
            the model is conditioned on vibration); the logged currents are ignored.

        Returns
        -------
        numpy.ndarray, shape (N, 2)
            ``[left, right]`` current (A) at ``log.time_s``.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        InvalidParameterError
            ``log`` is not an InteractionLog.
        DataError
            The log is too short for the model's windows.
        """
        self._check_log(log)
        out = np.asarray(self._predict(log), dtype=np.float64)
        if out.shape != (len(log), 2):  # internal contract of subclasses
            raise RuntimeError(f"{type(self).__name__}._predict returned shape {out.shape!r}, expected {(len(log), 2)!r}")
        return out

    def predict_distribution(self, log: InteractionLog) -> CurrentForecast:
        """The forecast of the log's drive currents with its interval (see :mod:`energy.models.forecast`).

        ``mean_a`` equals :meth:`predict`; ``run_sd_a`` is the spread shared by the whole run
        on one ground (what the model does not know about the ground plus how runs differ),
        ``sample_sd_a`` the spread independent per sample. A model without an interval
        (:attr:`gives_interval` False) returns zero spreads.

        Parameters
        ----------
        log : InteractionLog
            As for :meth:`predict`.

        Returns
        -------
        CurrentForecast
            Mean and spreads of the ``[left, right]`` currents (A) at ``log.time_s``.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        InvalidParameterError
            ``log`` is not an InteractionLog.
        DataError
            The log is too short for the model's windows.
        """
        self._check_log(log)
        return self._predict_distribution(log)

    def _check_log(self, log: InteractionLog) -> None:
        self._check_fitted()
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"log must be an InteractionLog, got {log!r:.80}")

    def _predict_distribution(self, log: InteractionLog) -> CurrentForecast:
        """The forecast of a checked log; models that see a spread of their own while predicting override it."""
        return self._with_interval(log, self.predict(log))

    def ground_vibration(self, ground: str) -> tuple[np.ndarray, np.ndarray] | None:
        """``(time_s, accel_z_mps2)`` recorded on ``ground`` in training, for a model conditioned on vibration; else None.

        A planner pricing a ground class of its map with such a model feeds it this stretch
        (the model cannot know the vibration of a ground it is not driving).
        """
        return None

    @property
    def gives_interval(self) -> bool:
        """Whether :meth:`predict_distribution` returns non-zero spreads (the model carries a fitted ``interval_``).

        The estimator fits one as it trains (its cross-validation ensemble); any other model
        gets one from :func:`energy.models.fit_interval`.
        """
        self._check_fitted()
        return getattr(self, "interval_", None) is not None

    def knows_ground(self, ground: str | None) -> bool:
        """Whether the model was trained on ``ground`` (case-insensitive; an unlabelled log counts as a new ground)."""
        summary = getattr(self, "trained_on_", None)
        if ground is None or summary is None:
            return False
        return str(ground).lower() in {g.lower() for g in summary.grounds}

    def _with_interval(self, log: InteractionLog, mean: np.ndarray, own_spread_a: np.ndarray | None = None
                       ) -> CurrentForecast:
        """``mean`` with the fitted interval's spreads (none without one); ``own_spread_a`` (N, 2) A is a spread the
        model saw itself while predicting (the estimator: its members' disagreement), added to the run-level one."""
        interval = getattr(self, "interval_", None)
        if interval is None:
            return CurrentForecast.point(log.time_s, mean)
        known = self.knows_ground(log.meta.ground_label)
        run = interval.run_sd_a(log, mean, known=known)
        if own_spread_a is not None:
            run = np.sqrt(run**2 + own_spread_a**2)
        return CurrentForecast(log.time_s, mean, run, interval.sample_sd(log),
                               interval.run_dof(log.meta.ground_label) if known else interval.new_ground_dof)

    def score(self, logs: InteractionLog | Sequence[InteractionLog]) -> float:
        """Coefficient of determination R² of the per-sample currents, both sides pooled.

        Raises
        ------
        NotFittedError, InvalidParameterError, DataError
            As :meth:`predict`; DataError also when the logged currents are constant.
        """
        self._check_fitted()
        items = check_logs(logs)
        truth = np.concatenate([log_currents(log) for log in items])
        pred = np.concatenate([self.predict(log) for log in items])
        ss_tot = float(np.sum((truth - truth.mean()) ** 2))
        if ss_tot == 0:
            raise DataError("score needs logged currents that vary; they are all equal")
        return 1.0 - float(np.sum((truth - pred) ** 2)) / ss_tot

    def adapt(self, log_prefix: InteractionLog | Sequence[InteractionLog], **options: Any) -> CurrentModel:
        """A new model updated on a short stretch of new data; this one is unchanged (see ``AdaptedCurrentModel``)."""
        return CurrentModel._registry["AdaptedCurrentModel"].adapting(self, log_prefix, **options)

    def _fit(self, logs: list[InteractionLog]) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _predict(self, log: InteractionLog) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    # -------------------------------------------------------------- persistence
    def _params_to_plain(self) -> dict[str, Any]:
        return self.get_params()

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        return dict(params)

    def _state(self) -> dict[str, Any]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _load_state(self, state: dict[str, Any]) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _versions(self) -> dict[str, str]:
        return package_versions()

    def to_record(self) -> ModelRecord:
        """The fitted model as a :class:`ModelRecord` (what :meth:`save` writes).

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        """
        self._check_fitted()
        summary = getattr(self, "trained_on_", None)
        interval = getattr(self, "interval_", None)
        return ModelRecord(type(self).__name__, self._params_to_plain(), self._state(), self._versions(),
                           trained_on=None if summary is None else summary.to_plain(),
                           interval=None if interval is None else interval.to_plain())

    @classmethod
    def from_record(cls, record: ModelRecord, source: str = "the record") -> CurrentModel:
        """Rebuild a fitted model from a :class:`ModelRecord` (the class must match, or be this base).

        Raises
        ------
        FileFormatError
            The record names another class, an unknown one, or its parameters or state do
            not make a valid model (missing or forged keys, wrong types, bad values).
        """
        name = record.model_class
        target = cls.registered(name)
        if target is None:
            raise FileFormatError(
                f"{source} holds an unknown model class {name!r:.80}; known: {sorted(CurrentModel._registry)!r}"
            )
        if cls is not CurrentModel and target is not cls:
            raise FileFormatError(f"{source} holds a {name}, not a {cls.__name__}")
        try:
            model = target(**target._params_from_plain(record.params))
            model._check_params()
            model._load_state(record.state)
        except FileFormatError as exc:  # a nested model (the estimator's physics prior)
            raise FileFormatError(f"{source}: {exc}") from exc
        except _FAILURES as exc:  # library errors on bad values are ValueErrors too
            raise FileFormatError(f"{source}: the {name} parameters or state are incomplete or inconsistent: {exc}") from exc
        if not model.is_fitted:
            raise FileFormatError(f"{source}: the {name} state restores no fitted attribute")
        if record.trained_on is not None:
            try:
                model.trained_on_ = TrainedOn.from_plain(record.trained_on)
            except _FAILURES as exc:
                raise FileFormatError(f"{source}: the training summary is malformed: {exc}") from exc
        if record.interval is not None:
            try:
                model.interval_ = IntervalModel.from_plain(record.interval)
            except _FAILURES as exc:
                raise FileFormatError(f"{source}: the forecast interval is incomplete or inconsistent: {exc}") from exc
        return model

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the fitted model to one file, atomically (temporary file, then rename).

        The file (a zip of ``model.json`` and ``.npy`` arrays; no pickle, no torch) holds
        the format and its version, the model class, the constructor parameters, the
        fitted state (weights, normalisers, ranges) and the package versions. Temporaries
        of saves killed earlier are removed first.

        Returns
        -------
        pathlib.Path

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        InvalidParameterError
            ``path`` is a directory, or lies under a file (checked before any work).
        """
        self._check_fitted()
        check_output_path(path, "path")
        return write_model_file(path, self.to_record())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> CurrentModel:
        """Read a model written by :meth:`save` (the class must match, or be this base).

        On the base class the stored class must have been imported; prefer
        :func:`energy.load_current_model`, which imports it.

        Raises
        ------
        FileFormatError
            Missing, corrupt, truncated or foreign file; forged or missing entries; a model
            of another class.
        FormatVersionError
            A file of another format version.
        """
        return cls.from_record(read_model_file(path), repr(str(path)))
