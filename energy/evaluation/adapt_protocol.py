"""The ``adapt`` evaluation protocol: a model adapted on the first seconds of a held-out run, scored on the rest.

For each held-out run (leave one run out per ground), the fitted model sees the run's first
``T`` seconds (each of ``adapt_seconds``), is adapted on them
(:class:`~energy.models.AdaptedCurrentModel`) and predicts the remainder; the remainder's
whole-run charge error, section error and RMSE are reported beside the unadapted model's
and the gain baseline's (one gain per side = measured / predicted charge of the same first
``T`` seconds) on the same samples. The ``"trigger"`` schedule is the adaptive loop's own
rule: every ``check_s`` seconds the charge error of the last ``check_s`` seconds is
compared with ``threshold_pct`` and, above it, the model is adapted on everything driven
so far; it is scored on the remainder after ``trigger_from_s``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_choice, check_real, check_text
from terrawatt_base.dask_client import check_client, run_tasks
from terrawatt_base.errors import DataError, InvalidParameterError

from ..battery import Battery
from ..logs import InteractionLog, run_names
from ..metrics import DEFAULT_SECTION_S, compare_currents
from ..models.adaptation import ADAPT_METHODS, ADAPT_SHRINKS, AdaptedCurrentModel
from ..models.base import CurrentModel, log_currents
from ..params import robot_params
from ..robot import RobotParams
from .adapt_results import TRIGGER_SCHEDULE, AdaptScore, summarise_adapt_scores
from .results import EvaluationResult, check_evaluation_dir
from .run_totals import RunTotal, ScoredRun, run_totals
from .scoring import check_runs, trim_to_overlap

__all__ = [
    "DEFAULT_ADAPT_SECONDS",
    "AdaptSettings",
    "adaptation_scores",
    "schedule_name",
    "named_models",
    "evaluate_adaptation",
    "collect_adaptation",
]

#: Prefix durations (s) of the ``adapt`` protocol.
DEFAULT_ADAPT_SECONDS = (10.0, 20.0, 40.0)
_trapezoid = getattr(np, "trapezoid", None) or np.trapz


def schedule_name(adapt_s: float) -> str:
    """The schedule label of a prefix: ``"20 s"``."""
    return f"{adapt_s:g} s"


@dataclass(frozen=True)
class AdaptSettings:
    """Settings of the ``adapt`` protocol (validated).

    Parameters
    ----------
    adapt_seconds : tuple of float
        Prefix durations T (s, > 0) the model is adapted on.
    trigger : bool
        Also run the running-error trigger schedule.
    threshold_pct : float
        Trigger: update when the last ``check_s`` seconds' charge error (both sides) exceeds it (%).
    check_s : float
        Trigger: seconds between checks (> 0).
    trigger_from_s : float
        Trigger: the scored remainder starts this many seconds into the run.
    min_remainder_s : float
        A run whose remainder after T is shorter is not scored for that T (listed as skipped).
    method, prior_s, turn_scale_radps, min_seconds, shrink
        The update (:class:`~energy.models.AdaptedCurrentModel`).
    section_s : float
        Section length of the section error (s).
    robot : str or RobotParams
        The robot that drove the logs (a preset name, a robot file or the parameters): its
        motors turn the currents into the pack energy of :class:`~energy.evaluation.RunTotal`.
    battery : Battery, optional
        Its pack (voltage, internal resistance); default the robot's nominal voltage, ideal.
    """

    adapt_seconds: tuple[float, ...] = DEFAULT_ADAPT_SECONDS
    trigger: bool = True
    threshold_pct: float = 10.0
    check_s: float = 8.0
    trigger_from_s: float = 20.0
    min_remainder_s: float = 10.0
    method: str = ADAPT_METHODS[0]
    prior_s: float = 20.0
    turn_scale_radps: float = 0.3
    min_seconds: float = 5.0
    shrink: str = ADAPT_SHRINKS[0]
    section_s: float = DEFAULT_SECTION_S
    robot: str | RobotParams = "husky"
    battery: Battery | None = None

    def __post_init__(self) -> None:
        own = "AdaptSettings"
        robot_params(self.robot, name=f"{own}.robot")  # a bad robot fails here, before any fold
        if self.battery is not None and not isinstance(self.battery, Battery):
            raise InvalidParameterError(f"{own}.battery must be a Battery or None, got {self.battery!r:.80}")
        seconds = self.adapt_seconds
        if isinstance(seconds, (str, bytes)) or not isinstance(seconds, Sequence) or not seconds:
            raise InvalidParameterError(f"{own}.adapt_seconds must be a non-empty sequence of seconds > 0, got {seconds!r:.80}")
        clean = tuple(check_real("adapt_seconds", s, low=0.0, low_inclusive=False, owner=own) for s in seconds)
        object.__setattr__(self, "adapt_seconds", clean)
        check_bool(f"{own}.trigger", self.trigger)
        check_real("threshold_pct", self.threshold_pct, low=0.0, owner=own)
        for name in ("check_s", "section_s", "prior_s", "turn_scale_radps"):
            check_real(name, getattr(self, name), low=0.0, low_inclusive=False, owner=own)
        for name in ("trigger_from_s", "min_remainder_s", "min_seconds"):
            check_real(name, getattr(self, name), low=0.0, owner=own)
        check_choice(f"{own}.method", self.method, ADAPT_METHODS)
        check_choice(f"{own}.shrink", self.shrink, ADAPT_SHRINKS)

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form."""
        d = asdict(self)
        d["adapt_seconds"] = list(self.adapt_seconds)
        d["robot"] = self.robot if isinstance(self.robot, str) else self.robot.name
        return d

    def robot_params(self) -> RobotParams:
        """The robot that drove the logs, as parameters."""
        return robot_params(self.robot, name="AdaptSettings.robot")

    def update_options(self) -> dict[str, Any]:
        """Keyword arguments of :class:`~energy.models.AdaptedCurrentModel` besides the base."""
        return {"method": self.method, "prior_s": self.prior_s, "turn_scale_radps": self.turn_scale_radps,
                "min_seconds": self.min_seconds, "shrink": self.shrink}


def _errors(t: np.ndarray, truth: np.ndarray, pred: np.ndarray, section_s: float) -> list[tuple[float, float, float]]:
    out = []
    for k in range(2):
        e = compare_currents(t, truth[:, k], pred[:, k], section_s)
        out.append((abs(e.whole_run_error_pct), e.section_error_pct, e.rmse_a))
    return out


def _gain(base_pred: np.ndarray, truth: np.ndarray, t: np.ndarray, sel: np.ndarray) -> np.ndarray:
    """The gain baseline's prediction: per side, measured / predicted charge of the samples ``sel``."""
    q_true = _trapezoid(truth[sel], t[sel], axis=0)
    q_pred = _trapezoid(base_pred[sel], t[sel], axis=0)
    gain = np.where(q_pred > 0, q_true / np.where(q_pred > 0, q_pred, 1.0), 1.0)
    return base_pred * gain[None, :]


def _prefix(log: InteractionLog, t_end: float) -> InteractionLog:
    return log.slice(float(log.time_s[0]), t_end)


def _triggered(model: CurrentModel, log: InteractionLog, base_pred: np.ndarray, settings: AdaptSettings
               ) -> tuple[np.ndarray, int]:
    """Predictions of the trigger schedule (each check's model predicts until the next check) and its update count."""
    t = log.time_s
    truth = np.abs(log_currents(log))
    out = base_pred.copy()
    current = base_pred
    n_updates = 0
    check = float(t[0]) + settings.check_s
    while check < t[-1]:
        seen = (t >= check - settings.check_s) & (t < check)
        q_true = float(np.sum(_trapezoid(truth[seen], t[seen], axis=0))) if np.count_nonzero(seen) > 1 else 0.0
        q_pred = float(np.sum(_trapezoid(np.abs(current[seen]), t[seen], axis=0))) if np.count_nonzero(seen) > 1 else 0.0
        if q_true > 0 and 100.0 * abs(q_pred - q_true) / q_true > settings.threshold_pct and check - t[0] >= settings.min_seconds:
            try:
                adapted = AdaptedCurrentModel(model, **settings.update_options()).fit(_prefix(log, check))
            except DataError:
                adapted = None  # too little data so far: keep the current model
            if adapted is not None:
                current = adapted.correct(log, base_pred)
                n_updates += 1
        later = t >= check
        out[later] = current[later]
        check += settings.check_s
    return out, n_updates


def adaptation_scores(
    model: CurrentModel,
    log: InteractionLog,
    *,
    run: str,
    model_name: str,
    settings: AdaptSettings | None = None,
) -> tuple[list[AdaptScore], list[RunTotal], list[str]]:
    """Score one fitted model on one held-out run under every schedule of ``settings``.

    Returns
    -------
    scores : list of AdaptScore
        Two per schedule (left, right) that the run is long enough for.
    totals : list of RunTotal
        Per schedule, the remainder's pack energy and total charge, unadapted, adapted and
        with the gain baseline (the trigger schedule's patchwork of updates has no interval).
    skipped : list of str
        The schedules left out and why.

    Raises
    ------
    InvalidParameterError
        ``model`` is not a CurrentModel, ``log`` not an InteractionLog, bad names or settings.
    NotFittedError
        ``model`` is not fitted.
    """
    settings = AdaptSettings() if settings is None else settings
    if not isinstance(settings, AdaptSettings):
        raise InvalidParameterError(f"settings must be an AdaptSettings, got {settings!r:.80}")
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a fitted CurrentModel, got {model!r:.80}")
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {log!r:.80}")
    check_text("run", run)
    check_text("model_name", model_name)
    t = log.time_s
    truth = log_currents(log)
    base_fc = model.predict_distribution(log)
    base_pred = base_fc.mean_a
    robot = settings.robot_params()
    ground = str(log.meta.ground_label)
    plans: list[tuple[str, float]] = [(schedule_name(s), s) for s in settings.adapt_seconds]
    if settings.trigger:
        plans.append((TRIGGER_SCHEDULE, settings.trigger_from_s))
    scores: list[AdaptScore] = []
    totals: list[RunTotal] = []
    skipped: list[str] = []
    for schedule, start in plans:
        rem = t >= t[0] + start
        remainder_s = float(t[-1] - (t[0] + start))
        if remainder_s < settings.min_remainder_s or np.count_nonzero(rem) < 3:
            skipped.append(f"{run} ({schedule}): {max(remainder_s, 0.0):.1f} s left after {start:g} s, "
                           f"less than min_remainder_s={settings.min_remainder_s:g}")
            continue
        n_updates = 0
        adapted_fc = None
        if schedule == TRIGGER_SCHEDULE:
            adapted, n_updates = _triggered(model, log, base_pred, settings)
        else:
            try:
                upd = AdaptedCurrentModel(model, **settings.update_options()).fit(_prefix(log, float(t[0] + start)))
            except DataError as exc:
                skipped.append(f"{run} ({schedule}): no adaptation ({exc})")
                continue
            adapted_fc, n_updates = upd.correct_distribution(log, base_fc), 1
            adapted = adapted_fc.mean_a
        gain = _gain(base_pred, truth, t, ~rem)
        e_none = _errors(t[rem], truth[rem], base_pred[rem], settings.section_s)
        e_adapt = _errors(t[rem], truth[rem], adapted[rem], settings.section_s)
        e_gain = _errors(t[rem], truth[rem], gain[rem], settings.section_s)
        for k, side in enumerate(("left", "right")):
            scores.append(AdaptScore(
                "per_ground", ground, run, run, model_name, side, schedule, float(start), remainder_s, n_updates,
                *e_none[k], *e_adapt[k], *e_gain[k]))
        totals += run_totals(log, {"unadapted": (base_pred, base_fc), "adapted": (adapted, adapted_fc),
                                   "gain": (gain, None)}, ScoredRun("per_ground", run, run, model_name, schedule),
                             robot=robot, battery=settings.battery, mask=rem)
    return scores, totals, skipped


def _adapt_fold(proto: CurrentModel, train: list[InteractionLog], test: InteractionLog, run: str,
                model_name: str, settings: AdaptSettings) -> tuple[list[AdaptScore], list[RunTotal], list[str]]:
    """Fit a fresh copy of ``proto`` on ``train`` and score it on ``test`` (module-level for dask)."""
    model = proto.clone().fit(train)
    return adaptation_scores(model, test, run=run, model_name=model_name, settings=settings)


def named_models(model: Any, name: str) -> dict[str, CurrentModel]:
    """``{name: model}`` for one model, or a mapping of named models, checked.

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel nor a non-empty mapping of str to CurrentModel; a bad ``name``.
    """
    if isinstance(model, CurrentModel):
        return {check_text("name", name): model}
    if not isinstance(model, Mapping) or not model:
        raise InvalidParameterError(f"model must be a CurrentModel or a non-empty mapping of names to them, got {model!r:.80}")
    for key, value in model.items():
        check_text("model name", key)
        if not isinstance(value, CurrentModel):
            raise InvalidParameterError(f"model[{key!r}] must be a CurrentModel, got {value!r:.80}")
    return dict(model)


def evaluate_adaptation(
    logs: Sequence[InteractionLog],
    model: CurrentModel | Mapping[str, CurrentModel],
    *,
    name: str = "model",
    settings: AdaptSettings | None = None,
    progress: bool = False,
    client: Any = None,
    out_dir: str | os.PathLike[str] | None = None,
) -> EvaluationResult:
    """The ``adapt`` protocol: leave one run out per ground, adapt on each held-out run's first seconds.

    Each log is cut to the span of both its streams; for every ground with at least two
    runs and every run of it, a fresh copy of ``model`` is fitted on the ground's other runs
    and scored on the run by :func:`adaptation_scores`.

    Parameters
    ----------
    logs : sequence of InteractionLog
        Runs with ``meta.ground_label`` set.
    model : CurrentModel or mapping of str to CurrentModel
        The prototype (not modified; ``clone()`` is fitted per fold), or several by name.
    name : str
        The model's name in the result (one model).
    settings : AdaptSettings, optional
        Schedules, update and scoring settings (defaults: T = 10, 20, 40 s and the trigger).
    progress : bool
        Show a progress bar over the folds.
    client : distributed.Client, optional
        Run the folds as tasks on a dask cluster (see :func:`evaluate_current_models`).
    out_dir : path-like, optional
        Folder to write the result's files into (:meth:`EvaluationResult.write`; checked before any work).

    Returns
    -------
    EvaluationResult
        Protocol ``"adapt"``.

    Raises
    ------
    InvalidParameterError
        Bad ``logs``, ``model``, ``name``, ``settings``, ``client`` or ``out_dir``.
    DataError
        A log without a ground label; no ground with two runs.
    """
    if out_dir is not None:
        check_evaluation_dir(out_dir, "adapt")
    settings = AdaptSettings() if settings is None else settings
    if not isinstance(settings, AdaptSettings):
        raise InvalidParameterError(f"settings must be an AdaptSettings, got {settings!r:.80}")
    models = named_models(model, name)
    items = check_runs(logs, labelled=True, what="the adapt protocol")
    check_client(client, "folds")
    items = [trim_to_overlap(lg) for lg in items]
    names = run_names(items)
    skipped: list[str] = []
    tasks = []
    for g in dict.fromkeys(lg.meta.ground_label for lg in items):
        idx = [i for i, lg in enumerate(items) if lg.meta.ground_label == g]
        if len(idx) < 2:
            skipped.append(f"ground {g!r} has {len(idx)} run; leave-one-run-out needs 2")
            continue
        tasks += [(_adapt_fold, (proto, [items[j] for j in idx if j != i], items[i], names[i], mname, settings))
                  for i in idx for mname, proto in models.items()]
    if not tasks:
        raise DataError("the adapt protocol needs a ground with at least 2 runs; none has")
    return collect_adaptation(tasks, settings, skipped, client=client, progress=progress, description="adapt folds",
                              out_dir=out_dir)


def collect_adaptation(tasks: list[tuple[Any, tuple[Any, ...]]], settings: AdaptSettings, skipped: list[str], *,
                       client: Any, progress: bool, description: str, out_dir: Any) -> EvaluationResult:
    """Run fold tasks (each returns ``(scores, totals, notes)``) here or on ``client``; the result,
    written to ``out_dir`` when given."""
    scores: list[AdaptScore] = []
    totals: list[RunTotal] = []
    notes_all = list(skipped)
    for rows, run_rows, notes in run_tasks(tasks, client=client, progress=progress, description=description):
        scores += rows
        totals += run_rows
        notes_all += notes
    if not scores:
        raise DataError(f"no run could be scored at any adapt time ({'; '.join(notes_all[:3]) or 'no runs'}"
                        f"{' ...' if len(notes_all) > 3 else ''})")
    protocol = {"per_ground": "adapt", "few_shot": "few-shot"}[scores[0].protocol]
    result = EvaluationResult(tuple(scores), summarise_adapt_scores(scores), protocol=protocol, totals=tuple(totals),
                              skipped=tuple(notes_all), settings=settings.to_dict())
    if out_dir is not None:
        result.write(out_dir)
    return result


