"""What a diagnosis works on, checked and prepared once: the logs, the model's prediction of them, the split into folds, the candidates bound to the logs and each stage's fitting data.

:func:`diagnosis_case` checks the model, the logs, the map, the robot and the settings, and
prepares in one pass everything the stages read: the model's (clamped) prediction of every log
(for the localisation), the :class:`Split` of the logs into folds (whole runs held out, or
contiguous blocks of every run) that hold out every sample exactly once, the candidate effects
the model lacks bound to the logs, and per stage a :class:`DiagnosisData` (the measured values,
the model's unclamped prediction of them, each candidate's per-log preparation and the split).
The fitting (:mod:`energy.diagnosis.fit`) and the selection read the prepared data alone; the
stages, the localisation and the corrected model take the checked logs from the case.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_choice, check_int, check_real, check_seed, readonly
from terrawatt_base.errors import DataError, InvalidParameterError, NotFittedError

from ..logs import InteractionLog
from ..models.base import CurrentModel, check_logs, log_currents
from ..params import robot_spec
from .effect_base import Effect
from .effects import LEARNED_EFFECT, effect, resolve_effects
from .model_currents import PhysicsBasis, clamps_at_zero, physics_basis, unclipped_prediction
from .model_source import ModelUnderDiagnosis
from .power_data import check_power_logs, power_inputs, power_logs_missing, predicted_battery_power_w
from .quantity import POWER
from .regimes import check_terrain

__all__ = ["SPLITS", "FitSettings", "Fold", "Split", "make_split", "DiagnosisData", "prepare_data", "DiagnosisCase",
           "diagnosis_case"]

#: Split kinds: whole runs held out, or contiguous blocks of every run.
SPLITS = ("runs", "blocks")


@dataclass(frozen=True, eq=False)
class Fold:
    """One fold: per log, boolean masks of the calibration and the held-out samples (never both)."""

    calibration: tuple[np.ndarray, ...]
    held_out: tuple[np.ndarray, ...]

    def __post_init__(self) -> None:
        if len(self.calibration) != len(self.held_out):
            raise InvalidParameterError("a Fold needs one calibration and one held-out mask per log")
        for k, (c, h) in enumerate(zip(self.calibration, self.held_out)):
            if c.shape != h.shape or c.dtype != bool or h.dtype != bool:
                raise InvalidParameterError(f"fold masks of log {k} must be boolean arrays of one shape")
            if np.any(c & h):
                raise InvalidParameterError(f"log {k}: a sample is both calibration and held out")
        object.__setattr__(self, "calibration", tuple(readonly(c) for c in self.calibration))
        object.__setattr__(self, "held_out", tuple(readonly(h) for h in self.held_out))

    @property
    def n_calibration(self) -> int:
        """Number of calibration samples."""
        return int(sum(int(c.sum()) for c in self.calibration))

    @property
    def n_held_out(self) -> int:
        """Number of held-out samples."""
        return int(sum(int(h.sum()) for h in self.held_out))


@dataclass(frozen=True, eq=False)
class Split:
    """Folds that hold out every sample exactly once, and the bootstrap unit of each sample.

    Attributes
    ----------
    kind : {"runs", "blocks"}
    folds : tuple of Fold
    units : tuple of numpy.ndarray
        Per log, the integer unit (a run, or a block of a run) of each sample; the
        bootstrap intervals resample these units.
    n_units : int
    """

    kind: str
    folds: tuple[Fold, ...]
    units: tuple[np.ndarray, ...]
    n_units: int

    def __post_init__(self) -> None:
        seen = [np.zeros(u.shape, dtype=np.int64) for u in self.units]
        for fold in self.folds:
            for k, h in enumerate(fold.held_out):
                seen[k] += h
        if any(np.any(s != 1) for s in seen):
            raise InvalidParameterError("a Split must hold out every sample exactly once")


def make_split(logs: Sequence[InteractionLog], kind: str = "runs", n_blocks: int = 5) -> Split:
    """Split ``logs`` into calibration and held-out parts.

    ``"runs"``: ``min(n_blocks, len(logs))`` folds of whole runs (run ``i`` in fold
    ``i % K``); ``"blocks"``: every run cut into ``n_blocks`` contiguous blocks of equal
    duration, fold ``k`` holding out block ``k`` of every run (never interleaved samples,
    which leak through autocorrelation).

    Raises
    ------
    UnknownNameError
        ``kind`` not in :data:`SPLITS`.
    InvalidParameterError
        ``n_blocks`` not an integer >= 2.
    DataError
        A split that leaves no held-out or no calibration data: ``"runs"`` with a single
        log, ``"blocks"`` with a run shorter than ``n_blocks`` samples.
    """
    check_choice("split", kind, SPLITS)
    n_blocks = check_int("n_blocks", n_blocks, low=2)
    sizes = [len(log) for log in logs]
    if kind == "runs":
        if len(logs) < 2:
            raise DataError(
                f"split='runs' needs at least 2 runs to hold one out, got {len(logs)}; use split='blocks' for a single run"
            )
        k = min(n_blocks, len(logs))
        units = tuple(np.full(n, i, dtype=np.int64) for i, n in enumerate(sizes))
        fold_of = [i % k for i in range(len(logs))]
        folds = tuple(
            Fold(tuple(np.full(n, fold_of[i] != f) for i, n in enumerate(sizes)),
                 tuple(np.full(n, fold_of[i] == f) for i, n in enumerate(sizes)))
            for f in range(k)
        )
        return Split("runs", folds, units, len(logs))
    short = [i for i, n in enumerate(sizes) if n < n_blocks]
    if short:
        raise DataError(
            f"split='blocks' with n_blocks={n_blocks} leaves no held-out data for run(s) {short!r} "
            f"({[sizes[i] for i in short]!r} samples)"
        )
    blocks = []
    for log in logs:
        t = log.time_s
        edges = np.linspace(t[0], t[-1], n_blocks + 1)
        b = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, n_blocks - 1)
        if np.unique(b).size != n_blocks:  # uneven clocks: fall back to equal sample counts
            b = (np.arange(len(log)) * n_blocks) // len(log)
        blocks.append(b)
    units = tuple(i * n_blocks + b for i, b in enumerate(blocks))
    folds = tuple(Fold(tuple(b != f for b in blocks), tuple(b == f for b in blocks)) for f in range(n_blocks))
    return Split("blocks", folds, units, len(logs) * n_blocks)


@dataclass(frozen=True)
class FitSettings:
    """How a diagnosis fits and scores its candidates: the split, the sections, the bootstrap (validated).

    Attributes
    ----------
    split : {"runs", "blocks"}
        Held-out data: other runs, or contiguous blocks of each run.
    n_blocks : int
        Folds of runs (at most the number of runs), or blocks per run (>= 2).
    seed : int or None
        Seed of the bootstrap intervals.
    section_s : float
        Section length of the section error and the time localisation (s), > 0.
    n_bootstrap : int
        Bootstrap resamples (>= 1).

    Raises
    ------
    UnknownNameError
        An unknown ``split``.
    InvalidParameterError
        A bad number.
    """

    split: str = "runs"
    n_blocks: int = 5
    seed: int | None = 0
    section_s: float = 8.0
    n_bootstrap: int = 200

    def __post_init__(self) -> None:
        check_choice("split", self.split, SPLITS)
        object.__setattr__(self, "n_blocks", check_int("n_blocks", self.n_blocks, low=2))
        object.__setattr__(self, "seed", check_seed(self.seed))
        object.__setattr__(self, "section_s", check_real("section_s", self.section_s, low=0.0, low_inclusive=False))
        object.__setattr__(self, "n_bootstrap", check_int("n_bootstrap", self.n_bootstrap, low=1))

    @property
    def held(self) -> str:
        """``"held-out runs"`` or ``"held-out blocks"``: the verdict's words for the scored data."""
        return "held-out runs" if self.split == "runs" else "held-out blocks"


@dataclass(frozen=True, eq=False)
class DiagnosisData:
    """Everything a stage fits and scores, computed once.

    The measured values (per log ``(N, C)``: the two side currents, or the battery power), the
    model's unclamped prediction of them, whether it clamps at 0, each candidate's per-log
    precomputation (by effect name), the :class:`Split` that scores them (None where only a fit
    on all samples is asked for: the corrected model), the physics basis the prediction stands
    on and, for the battery power, per log 1 where the robot stands still.
    """

    logs: tuple[InteractionLog, ...]
    measured: tuple[np.ndarray, ...]
    base: tuple[np.ndarray, ...]
    clip: bool
    prepared: dict[str, tuple[Any, ...]]
    split: Split | None = None
    basis: PhysicsBasis | None = None
    stopped: tuple[np.ndarray, ...] | None = None

    @property
    def n_samples(self) -> int:
        """Number of drive samples over all logs."""
        return int(sum(m.shape[0] for m in self.measured))

    @property
    def n_columns(self) -> int:
        """Measured values per sample (2 side currents; 1 battery power)."""
        return int(self.measured[0].shape[1]) if self.measured else 2


def prepare_data(model: Any, logs: Sequence[InteractionLog], effects: Sequence[Effect],
                 basis: PhysicsBasis | None = None, split: Split | None = None) -> DiagnosisData:
    """Measured currents, the model's unclamped predictions and every effect's per-log preparation."""
    measured = tuple(log_currents(log) for log in logs)
    base = tuple(unclipped_prediction(model, log, basis) for log in logs)
    prepared = {e.name: tuple(e.prepare(model, log) for log in logs) for e in effects}
    return DiagnosisData(tuple(logs), measured, base, clamps_at_zero(model), prepared, split, basis)


def _power_data(model: Any, logs: list[InteractionLog], electrical: list[Effect], split: Split, basis: PhysicsBasis,
                robot: Any) -> tuple[DiagnosisData, list[Effect]]:
    """The power stage's data and its candidates bound to the logs: voltage x pack current of every log, and the
    basis's battery power from the measured drive currents (:mod:`energy.diagnosis.power_data`)."""
    check_power_logs(logs)
    candidates = [e.bind(logs, None, robot) for e in electrical]
    inputs = [power_inputs(basis, log) for log in logs]
    measured = tuple(POWER.measured(log) for log in logs)
    base = tuple(predicted_battery_power_w(i)[:, None] for i in inputs)
    prepared = {e.name: tuple(e.prepare(model, log) for log in logs) for e in candidates}
    return (DiagnosisData(tuple(logs), measured, base, False, prepared, split, basis, tuple(i.stopped for i in inputs)),
            candidates)


@dataclass(frozen=True, eq=False)
class DiagnosisCase:
    """What is diagnosed, checked once (:func:`diagnosis_case`).

    Attributes
    ----------
    model : CurrentModel
        The fitted model as given.
    logs : list of InteractionLog
        The runs, each with at least 2 drive samples and drive currents.
    terrain : TerrainMap or None
    robot : Any
        The reference robot (None: the model's own, or the preset default).
    settings : FitSettings
    note : str
        Where the model comes from (a ModelUnderDiagnosis), else ``""``.
    predictions : tuple of numpy.ndarray
        The model's ``(N, 2)`` prediction of each log, as it predicts (clamped).
    data : DiagnosisData
        The current stage's data: every usable candidate and the learned one prepared, with the split.
    candidates : tuple of Effect
        The current stage's catalogued candidates, bound to the logs.
    learned : Effect or None
        The learned residual correction, scored where nothing else is significant.
    learned_requested : bool
        Whether the candidates were named (the learned correction is then added only when named).
    skipped : dict of str to str
        Candidates not scored and why.
    power : DiagnosisData or None
        The power stage's data, when every log carries battery voltage and pack current and there are
        electrical candidates.
    power_candidates : tuple of Effect
        The electrical candidates, bound to the logs.
    """

    model: CurrentModel
    logs: list[InteractionLog]
    terrain: Any
    robot: Any
    settings: FitSettings
    note: str
    predictions: tuple[np.ndarray, ...]
    data: DiagnosisData
    candidates: tuple[Effect, ...]
    learned: Effect | None
    learned_requested: bool
    skipped: dict[str, str]
    power: DiagnosisData | None = None
    power_candidates: tuple[Effect, ...] = ()

    @property
    def split(self) -> Split:
        """The folds every stage is scored on."""
        return self.data.split


def diagnosis_case(model: CurrentModel | ModelUnderDiagnosis, logs: InteractionLog | Sequence[InteractionLog], *,
                   terrain: Any = None, effects: Sequence[Any] | None = None, settings: FitSettings | None = None,
                   robot: Any = None) -> DiagnosisCase:
    """Check what :func:`energy.diagnosis.diagnose` is asked and prepare every stage's data once.

    The parameters are :func:`~energy.diagnosis.diagnose`'s (but ``compute``); so are the errors.

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel, bad logs, settings that are not a FitSettings, a ``robot`` beside a
        ModelUnderDiagnosis.
    NotFittedError
        An unfitted model.
    UnknownNameError
        An effect name not in the catalogue.
    DataError
        Logs without currents, a model that cannot predict the logs, a split that leaves no
        held-out data, a battery voltage <= 0 where a pack current is logged.
    """
    note = ""
    if isinstance(model, ModelUnderDiagnosis):
        if robot is not None:
            raise InvalidParameterError("robot must be None with a ModelUnderDiagnosis, which brings its own "
                                        f"reference robot; got {robot!r:.80}")
        note, robot, model = model.note, model.reference_robot, model.model
    settings = FitSettings() if settings is None else settings
    if not isinstance(settings, FitSettings):
        raise InvalidParameterError(f"settings must be a FitSettings, got {type(settings).__name__!r}")
    items = _checked_logs(logs)
    if robot is not None:
        robot = robot_spec(robot)  # a robot file read once: the corrected model keeps its parameters, not a path
    terrain = check_terrain(terrain)
    predictions = _check_model(model, items)
    sp = make_split(items, settings.split, settings.n_blocks)
    resolved = resolve_effects(effects)
    electrical = [e for e in resolved if e.kind == "electrical"]
    usable, learned, skipped = _candidates(model, items, [e for e in resolved if e.kind != "electrical"], effects,
                                           terrain, robot)
    basis = physics_basis(model, robot)
    power, bound = None, []
    if electrical and not power_logs_missing(items):
        power, bound = _power_data(model, items, electrical, sp, basis, robot)
    elif electrical and effects is not None:  # asked for by name on logs without battery power
        skipped.update({e.name: e.unsupported(items, terrain) or "" for e in electrical})
    data = prepare_data(model, items, usable + ([learned] if learned is not None else []), basis, sp)
    return DiagnosisCase(model, items, terrain, robot, settings, note, tuple(predictions), data, tuple(usable),
                         learned, effects is not None, skipped, power, tuple(bound))


def _checked_logs(logs: Any) -> list[InteractionLog]:
    """``logs`` as a list (:func:`check_logs`), each with at least 2 drive samples and drive currents not all zero."""
    items = check_logs(logs)
    for k, log in enumerate(items):
        if len(log) < 2:
            raise DataError(f"logs[{k}] has {len(log)} drive sample(s); the diagnosis needs at least 2 per log")
        log.require_currents("the diagnosis")
        if not (np.any(log.current_left_a) or np.any(log.current_right_a)):
            raise DataError(f"logs[{k}] ({log.meta.source!r}) has no drive currents (all zero); "
                            "the diagnosis compares measured and predicted currents")
    return items


def _check_model(model: Any, logs: list[InteractionLog]) -> list[np.ndarray]:
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a fitted CurrentModel, got {type(model).__name__!r}")
    if not model.is_fitted:
        raise NotFittedError(f"model {type(model).__name__} is not fitted; fit it (or load a saved one) before diagnosing")
    out = []
    for k, log in enumerate(logs):
        try:
            pred = np.asarray(model.predict(log), dtype=np.float64)
        except (DataError, InvalidParameterError, ValueError, KeyError, AttributeError) as exc:
            raise DataError(f"the {type(model).__name__} cannot predict logs[{k}] ({log.meta.source!r}): {exc}") from exc
        if pred.shape != (len(log), 2) or not np.all(np.isfinite(pred)):
            raise DataError(f"the {type(model).__name__} gives no finite (N, 2) prediction for logs[{k}]")
        out.append(pred)
    return out


def _candidates(model: Any, logs: list[InteractionLog], items: list[Effect], effects: Any, terrain: Any,
                robot: Any) -> tuple[list[Effect], Effect | None, dict[str, str]]:
    skipped: dict[str, str] = {}
    usable: list[Effect] = []
    learned: Effect | None = None
    for e in items:
        if not e.applies_to(model):
            skipped[e.name] = "already in the model, or not applicable to it"
            continue
        why = e.unsupported(logs, terrain, model)
        if why:
            skipped[e.name] = why
            continue
        bound = e.bind(logs, terrain, robot)
        if e.name == LEARNED_EFFECT:
            learned = bound
        elif bound.n_parameters:
            usable.append(bound)
    if learned is None and effects is None:
        learned = effect(LEARNED_EFFECT)
    return usable, learned, skipped
