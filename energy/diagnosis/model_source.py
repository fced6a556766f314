"""The model a diagnosis diagnoses: the physics as given or fitted on calibration runs, the estimator, or a file."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain.terrain_map import TerrainMap
from terrawatt_base.checks import check_bool, check_seed, fmt_number
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from ..logs import InteractionLog, named_robots, rest_samples, robot_matches
from ..models.base import CurrentModel
from ..models.baselines import PhysicsCurrentModel
from ..models.kinds import new_current_model
from ..models.loading import load_current_model
from ..params import GROUND_PRESETS, RobotParams, robot_params, robot_spec
from .model_currents import DRIVE_EFFECTS

__all__ = ["MODEL_SOURCES", "ModelUnderDiagnosis", "check_model_source",
           "check_calibration_logs", "model_under_diagnosis", "MIN_CALIBRATION_DRIVING_S"]

#: The model sources named by a word; anything else is a saved model file.
MODEL_SOURCES = ("physics", "estimator")


@dataclass(frozen=True)
class ModelUnderDiagnosis:
    """A fitted model to diagnose and a sentence saying where it comes from.

    Attributes
    ----------
    model : CurrentModel
        Fitted, never on the logs it diagnoses.
    note : str
        Where it comes from (:attr:`energy.diagnosis.Diagnosis.model_note`).
    kind : {"physics", "estimator", "file"}
    robot : str or None
        The robot preset asked for; for a model that is not the physics, the robot of the
        diagnosis' reference physics (:func:`energy.diagnose`'s ``robot``).
    """

    model: CurrentModel
    note: str
    kind: str
    robot: str | None = None

    @property
    def reference_robot(self) -> str | None:
        """``robot`` for :func:`energy.diagnose`: None for the physics model (it is its own reference)."""
        return None if self.kind == "physics" else self.robot




def check_model_source(model: str | os.PathLike[str], *, calibration: Any = None, robot: str | None = None,
                       ground: str | None = None, without: Sequence[str] = ()) -> str:
    """Check a model source and the options that go with it, before any work; return its kind.

    Parameters
    ----------
    model : str or path-like
        ``"physics"`` (the robot and ground presets), ``"estimator"`` (trained on the
        calibration runs) or a saved model file.
    calibration : any, optional
        The calibration runs, or anything that stands for them (e.g. their path); None for none.
    robot, ground : str, optional
        Robot and (physics only) starting ground presets.
    without : sequence of str
        Physics only: drive effects (:data:`DRIVE_EFFECTS`) switched off, each once.

    Returns
    -------
    str
        ``"physics"``, ``"estimator"`` or ``"file"``.

    Raises
    ------
    InvalidParameterError
        Not a source word nor a file; ``ground`` or ``without`` for another model than the
        physics; calibration runs for a file; the estimator without them; an effect twice.
    UnknownNameError
        A robot or ground that is no preset, an effect that is no drive effect.

    Each error names the argument(s) it is about (:attr:`~terrawatt_base.errors.TerrawattError.parameter`; in
    backticks in the message, ```model```), so a front end can say them its own way.

    Examples
    --------
    >>> check_model_source("physics", without=["inertia"])
    'physics'
    """
    if not isinstance(model, (str, os.PathLike)):
        raise InvalidParameterError(f"`model` must be a string or a path, got {type(model).__name__}",
                                    parameter="model")
    kind = str(model) if str(model) in MODEL_SOURCES else "file"
    if kind == "file" and not Path(model).is_file():
        raise InvalidParameterError(f"`model` must be 'physics', 'estimator' or a model file; {str(model)!r} is "
                                    "no file", parameter="model")
    if robot is not None:
        robot_params(robot)  # a preset, or a robot file read (and checked) now
    without = list(without)
    if kind != "physics":
        for key, value in (("ground", ground), ("without", without)):
            if value:
                raise InvalidParameterError(f"`{key}` applies to `model` physics only, got `model` {str(model)!r}",
                                            parameter=(key, "model"))
    if kind == "file" and calibration is not None:
        raise InvalidParameterError("`calibration` applies to `model` physics or estimator; a saved model is "
                                    "diagnosed as it is", parameter=("calibration", "model"))
    if kind == "estimator" and calibration is None:
        raise InvalidParameterError("`model` estimator needs `calibration`: the estimator has no preset, and training "
                                    "it on the logs it diagnoses would hide the gap (or give a saved model file)",
                                    parameter=("model", "calibration"))
    if ground is not None and ground not in GROUND_PRESETS:
        raise UnknownNameError(f"`ground` {ground!r} is not a ground preset; known: {sorted(GROUND_PRESETS)!r}",
                               parameter="ground")
    bad = [e for e in without if e not in DRIVE_EFFECTS]
    if bad:
        raise UnknownNameError(f"`without` {bad!r}: not physics drive effects; expected names from "
                               f"{list(DRIVE_EFFECTS)!r}", parameter="without")
    if len(set(without)) != len(without):
        raise InvalidParameterError(f"`without` names an effect twice: {without!r}", parameter="without")
    return kind


def _runs(logs: Sequence[InteractionLog]) -> str:
    return f"{len(logs)} run{'s' if len(logs) != 1 else ''}"


def _labels(logs: Sequence[InteractionLog]) -> set[str] | None:
    """The ground labels the logs drive on (per sample, or each run's label); None if a log has none."""
    found: set[str] = set()
    for log in logs:
        labels = log.ground_labels
        if labels is None:
            return None
        found.update(str(g) for g in set(labels.tolist()))
    return found


def _physics_ground(ground: str | None, labels: set[str] | None, needed: set[str] | None) -> str | dict[str, str]:
    """The ground(s) of the physics: as asked; else the logs' one preset, or a preset per label when they
    drive on several presets that cover the ``needed`` labels (those of the diagnosed logs); else asphalt."""
    if ground is not None:
        return ground
    if labels and labels <= set(GROUND_PRESETS):
        if len(labels) == 1:
            return next(iter(labels))
        if needed is not None and needed <= labels:
            return {g: g for g in sorted(labels)}
    return "asphalt"


def _ground_text(ground: str | dict[str, str]) -> str:
    return ground if isinstance(ground, str) else ", ".join(ground) + " (a preset per ground label)"


def _physics_robot(robot: str | os.PathLike[str] | None) -> tuple[str | RobotParams, str]:
    """The robot of the physics model (a preset by its name, as model files keep it; a robot file's
    :class:`RobotParams`) and how the note names it."""
    spec = robot_spec("husky" if robot is None else robot)
    if isinstance(spec, str):
        return spec, spec
    return spec, f"{spec.name} (robot file {Path(robot).name})" if isinstance(robot, (str, os.PathLike)) else spec.name


#: Least driving (s, moving samples over all runs) a model can be calibrated on: below it the fit
#: has fewer samples than a drive's few seconds of transients (a one-second run is refused).
MIN_CALIBRATION_DRIVING_S = 5.0
#: Below this much driving (s) the calibration is used but the note says its coefficients are uncertain.
SHORT_CALIBRATION_DRIVING_S = 60.0
_NO_CURRENT_A = 1e-6


def _driving_s(log: InteractionLog) -> float:
    """Seconds of driving (moving samples, each standing for its share of the clock) in ``log``."""
    if len(log) < 2:
        return 0.0
    return float(np.sum(np.gradient(log.time_s)[~rest_samples(log)]))


def _content_key(log: InteractionLog) -> bytes:
    """A digest of what a run measured (commands and currents, not its clock or its name): equal for a copy."""
    h = hashlib.sha256()
    for arr in (log.v_mps, log.omega_radps, log.current_left_a, log.current_right_a):
        h.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    return h.digest()


def check_calibration_logs(cal: Sequence[InteractionLog], logs: Sequence[InteractionLog], *,
                           robot: str | os.PathLike[str] | None = None) -> str:
    """Check that ``cal`` can calibrate a model to diagnose ``logs``; returns a note ("" or what to beware of).

    Calibration runs must be other runs of the same robot with currents: a copy of a diagnosed
    run (same file, or the same commands and currents under another name) would fit the model to
    the gap it is meant to find; runs with no current (all zero) or with no driving teach the fit
    nothing; another robot's runs (a Jackal's logs for a Husky model) calibrate another machine.

    Parameters
    ----------
    cal, logs : sequence of InteractionLog
        The calibration runs and the diagnosed runs.
    robot : str or path-like, optional
        The physics' robot (a preset name, or a robot file whose robot name is compared); None
        compares the runs' robots with each other only.

    Returns
    -------
    str
        ``""``, or a clause for the model's note when the calibration drives less than
        :data:`SHORT_CALIBRATION_DRIVING_S`.

    Raises
    ------
    InvalidParameterError
        A calibration run that is a diagnosed run (by source or by content), one without
        current, of another robot, or less than :data:`MIN_CALIBRATION_DRIVING_S` of driving in all. The
        message names the runs as ```calibration_logs``` and ```logs``` (:func:`model_under_diagnosis`' arguments,
        the error's :attr:`~terrawatt_base.errors.TerrawattError.parameter`).
    """
    cal_flag, logs_flag, both = "`calibration_logs`", "`logs`", ("calibration_logs", "logs")
    if not cal or not all(isinstance(log, InteractionLog) for log in cal):
        raise InvalidParameterError(f"{cal_flag} must be a non-empty sequence of InteractionLog",
                                    parameter="calibration_logs")
    diagnosed = {log.meta.source for log in logs if log.meta.source}
    shared = sorted({log.meta.source for log in cal} & diagnosed)
    if shared:
        raise InvalidParameterError(f"{cal_flag} holds runs that {logs_flag} diagnoses too: {shared[:3]!r}; "
                                    "calibrate on runs that are not diagnosed", parameter=both)
    keys = {_content_key(log): log.meta.source for log in logs}
    copies = [(log.meta.source, keys[k]) for log in cal if (k := _content_key(log)) in keys]
    if copies:
        raise InvalidParameterError(
            f"{cal_flag} holds copies of diagnosed runs (the same commands and currents): "
            f"{', '.join(f'{a!r} = {b!r}' for a, b in copies[:3])}; calibrate on runs that are not diagnosed",
            parameter="calibration_logs")
    silent = [log.meta.source for log in cal
              if not (np.nanmax(np.abs(np.concatenate([log.current_left_a, log.current_right_a])), initial=0.0)
                      > _NO_CURRENT_A)]
    if silent:
        raise InvalidParameterError(
            f"{cal_flag} holds runs without drive current (every sample 0 A): {silent[:3]!r}; a model cannot be "
            "calibrated on them: check the current columns or topics", parameter="calibration_logs")
    spec = None if robot is None else robot_spec(robot)
    target = named_robots(log.meta.robot for log in logs)
    if spec is not None:
        target = [spec if isinstance(spec, str) else spec.name]
    cal_robots = named_robots(log.meta.robot for log in cal)
    other = [r for r in cal_robots if target and not any(robot_matches(t, r) or robot_matches(r, t) for t in target)]
    if other:
        raise InvalidParameterError(
            f"{cal_flag} holds runs of robot(s) {other!r}, not of {target!r} that {logs_flag} diagnoses: calibrate on "
            "runs of the same robot", parameter=both)
    driving = sum(_driving_s(log) for log in cal)
    if driving < MIN_CALIBRATION_DRIVING_S:
        raise InvalidParameterError(
            f"{cal_flag} drives {fmt_number(driving, 3)} s in all, fewer than the {fmt_number(MIN_CALIBRATION_DRIVING_S)} "
            "s a calibration needs; give longer runs", parameter="calibration_logs")
    if driving < SHORT_CALIBRATION_DRIVING_S:
        return (f" (only {fmt_number(driving, 3)} s of driving: its coefficients are uncertain, and so is what the "
                "diagnosis attributes to them)")
    return ""


def model_under_diagnosis(model: str | os.PathLike[str], logs: Sequence[InteractionLog], *,
                          calibration_logs: Sequence[InteractionLog] | None = None,
                          calibration_label: str = "the calibration logs", robot: str | None = None,
                          ground: str | None = None, without: Sequence[str] = (), seed: int | None = 0,
                          progress: bool = False, terrain: TerrainMap | None = None) -> ModelUnderDiagnosis:
    """The model to diagnose on ``logs``, never fitted on them, and where it comes from.

    ``"physics"``: the ``robot`` (default husky) and ``ground`` presets as given, or their
    coefficients fitted on ``calibration_logs``; ``without`` switches drive effects off.
    Without ``ground``, the logs' ground: their one preset, or — when they drive on several
    presets (per-sample labels, as a mission's logs) — each sample on its own label's preset,
    as a planner prices each cell (calibrated: per-label coefficients, when the calibration
    runs cover every diagnosed label); else asphalt. As given on ``terrain`` with poses in
    every log, the physics drives the map's slope under the logged poses, as the planner
    priced it (the ``slope`` candidate is then part of the model); otherwise level ground.
    ``"estimator"``: the vibration estimator trained on ``calibration_logs``. A file: the
    saved model, as it is.

    Parameters
    ----------
    model : str or path-like
        ``"physics"``, ``"estimator"`` or a saved model file (:func:`check_model_source`).
    logs : sequence of InteractionLog
        The logs to diagnose.
    calibration_logs : sequence of InteractionLog, optional
        Other runs to fit the physics' coefficients on or to train the estimator on; none of
        them a diagnosed run (by ``meta.source``).
    calibration_label : str
        How the note names the calibration runs (e.g. their folder).
    robot, ground, without
        As :func:`check_model_source`.
    seed : int or None
        Seed of the estimator's training.
    progress : bool
        The estimator's progress bar.
    terrain : TerrainMap, optional
        The map the diagnosed runs drove on (the physics as given drives its slope).

    Returns
    -------
    ModelUnderDiagnosis

    Raises
    ------
    InvalidParameterError
        As :func:`check_model_source`; calibration runs that are also diagnosed; no logs.
    UnknownNameError
        As :func:`check_model_source`.
    TerrawattError
        As the models' ``fit`` and :func:`energy.load_current_model`.
    """
    kind = check_model_source(model, calibration=calibration_logs, robot=robot, ground=ground, without=without)
    seed = check_seed(seed)
    progress = check_bool("progress", progress)
    logs = list(logs)
    if not logs or not all(isinstance(log, InteractionLog) for log in logs):
        raise InvalidParameterError("logs must be a non-empty sequence of InteractionLog")
    cal = None if calibration_logs is None else list(calibration_logs)
    short_note = ""
    if cal is not None:
        short_note = check_calibration_logs(cal, logs, robot=robot if kind == "physics" else None)
    if terrain is not None and not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap or None, got {type(terrain).__name__!r}")
    if kind == "physics":
        physics_robot, robot_name = _physics_robot(robot)
        effects = None if not without else tuple(e for e in DRIVE_EFFECTS if e not in without)
        off = f" without {', '.join(without)}" if without else " (every drive effect)"
        if cal is None:
            ground_of = _physics_ground(ground, _labels(logs), _labels(logs))
            on_map = terrain is not None and all(log.pose_xyh is not None for log in logs)
            fitted = PhysicsCurrentModel(physics_robot, ground_of, fit_parameters=(), effects=effects,
                                         terrain=terrain if on_map else None).fit(logs)
            where = " on the map's slope under the logged poses" if on_map else ""
            return ModelUnderDiagnosis(fitted, (
                f"physics, the {robot_name} and {_ground_text(ground_of)} presets as given{off}{where}, not fitted on "
                f"the {_runs(logs)} it is diagnosed on (calibration_logs fits its coefficients on other runs)"),
                kind, robot)
        ground_of = _physics_ground(ground, _labels(cal), _labels(logs))
        fitted = PhysicsCurrentModel(physics_robot, ground_of, effects=effects).fit(cal)
        values = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in fitted.fitted_.items())
        return ModelUnderDiagnosis(fitted, (
            f"physics, {robot_name} starting from {_ground_text(ground_of)}{off}; its coefficients fitted on the "
            f"{_runs(cal)} of {calibration_label} ({values}), which are not diagnosed{short_note}"), kind, robot)
    if kind == "estimator":
        trained = new_current_model("estimator", seed=seed, progress=progress).fit(cal)
        return ModelUnderDiagnosis(trained, (f"the vibration estimator, trained on the {_runs(cal)} of "
                                             f"{calibration_label}, which are not diagnosed{short_note}"), kind, robot)
    loaded = load_current_model(model)
    return ModelUnderDiagnosis(loaded, f"{type(loaded).__name__} loaded from {model}", kind, robot)
