"""Few shots on unknown ground: a model trained on other grounds, adapted on seconds of one run of a new one.

For each target ground, a fresh copy of the model is fitted on every run of the *other*
grounds; then for every run of the target ground long enough and every ``T`` of
``adapt_seconds``, the model is adapted on that run's first ``T`` seconds and scored on each
*other* run of the target ground, whole, beside the unadapted model and the gain baseline
(gains from the same ``T`` seconds). This is the source method's premise: the geology is
unknown until driven on.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from terrawatt_base.checks import check_text
from terrawatt_base.dask_client import check_client
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog, run_names
from ..metrics import compare_currents
from ..models.adaptation import AdaptedCurrentModel
from ..models.base import CurrentModel, log_currents
from .adapt_protocol import AdaptSettings, collect_adaptation, named_models, schedule_name
from .adapt_results import AdaptScore
from .results import EvaluationResult, check_evaluation_dir
from .run_totals import RunTotal, ScoredRun, run_totals
from .scoring import check_runs, trim_to_overlap

__all__ = ["few_shot_scores", "evaluate_few_shot"]

_trapezoid = getattr(np, "trapezoid", None) or np.trapz


def _errs(log: InteractionLog, pred: np.ndarray, section_s: float) -> list[tuple[float, float, float]]:
    truth = log_currents(log)
    out = []
    for k in range(2):
        e = compare_currents(log.time_s, truth[:, k], pred[:, k], section_s)
        out.append((abs(e.whole_run_error_pct), e.section_error_pct, e.rmse_a))
    return out


def few_shot_scores(
    model: CurrentModel,
    runs: Sequence[InteractionLog],
    names: Sequence[str],
    *,
    model_name: str,
    settings: AdaptSettings | None = None,
) -> tuple[list[AdaptScore], list[RunTotal], list[str]]:
    """Score a model fitted without the runs' ground: adapt on each run's first seconds, test on the others.

    Parameters
    ----------
    model : CurrentModel
        Fitted on other grounds.
    runs : sequence of InteractionLog
        The target ground's runs (at least 2).
    names : sequence of str
        Their names in the scores.
    model_name : str
    settings : AdaptSettings, optional
        Its ``adapt_seconds``, update and ``section_s`` are used (the trigger is not: the
        scored runs are whole other runs).

    Returns
    -------
    scores : list of AdaptScore
        Protocol ``"few_shot"``: one per adaptation run, T, test run and side.
    totals : list of RunTotal
        One per adaptation run, T, test run and variant: the test run's pack energy and total
        charge, unadapted, adapted and with the gain baseline.
    skipped : list of str
        Adaptation runs shorter than T + ``min_seconds`` (nothing left after T would be
        needed, but the update needs its seconds).

    Raises
    ------
    InvalidParameterError
        Fewer than 2 runs, names that do not match, bad settings.
    """
    settings = AdaptSettings() if settings is None else settings
    if not isinstance(settings, AdaptSettings):
        raise InvalidParameterError(f"settings must be an AdaptSettings, got {settings!r:.80}")
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a fitted CurrentModel, got {model!r:.80}")
    items, labels = list(runs), [str(n) for n in names]
    if len(items) < 2 or len(labels) != len(items) or not all(isinstance(r, InteractionLog) for r in items):
        raise InvalidParameterError(f"runs must be at least 2 InteractionLogs with one name each, got {len(items)} "
                                    f"runs and {len(labels)} names")
    check_text("model_name", model_name)
    robot = settings.robot_params()
    base_fc = [model.predict_distribution(r) for r in items]
    base = [fc.mean_a for fc in base_fc]
    plain = [_errs(r, p, settings.section_s) for r, p in zip(items, base)]
    scores: list[AdaptScore] = []
    totals: list[RunTotal] = []
    skipped: list[str] = []
    for a, run_a in enumerate(items):
        t = run_a.time_s
        for T in settings.adapt_seconds:
            schedule = schedule_name(T)
            if run_a.duration_s < T:
                skipped.append(f"{labels[a]} ({schedule}): the run lasts {run_a.duration_s:.1f} s, less than {T:g} s")
                continue
            prefix = run_a.slice(float(t[0]), float(t[0] + T))
            try:
                # the other runs of the ground are forecast: a Bayesian update carries its ground offset only
                upd = AdaptedCurrentModel(model, **settings.update_options(), scope="ground").fit(prefix)
            except DataError as exc:
                skipped.append(f"{labels[a]} ({schedule}): no adaptation ({exc})")
                continue
            sel = t < t[0] + T
            truth = log_currents(run_a)
            q_true = _trapezoid(truth[sel], t[sel], axis=0)
            q_pred = _trapezoid(base[a][sel], t[sel], axis=0)
            gain = np.where(q_pred > 0, q_true / np.where(q_pred > 0, q_pred, 1.0), 1.0)
            for b, run_b in enumerate(items):
                if b == a:
                    continue
                fc_ad = upd.correct_distribution(run_b, base_fc[b])
                pred_g = base[b] * gain[None, :]
                e_ad = _errs(run_b, fc_ad.mean_a, settings.section_s)
                e_g = _errs(run_b, pred_g, settings.section_s)
                totals += run_totals(run_b, {"unadapted": (base[b], base_fc[b]), "adapted": (fc_ad.mean_a, fc_ad),
                                             "gain": (pred_g, None)},
                                     ScoredRun("few_shot", labels[b], labels[a], model_name, schedule), robot=robot,
                                     battery=settings.battery)
                for k, side in enumerate(("left", "right")):
                    scores.append(AdaptScore(
                        "few_shot", str(run_b.meta.ground_label), labels[b], labels[a], model_name, side, schedule,
                        float(T), run_b.duration_s, 1, *plain[b][k], *e_ad[k], *e_g[k]))
    return scores, totals, skipped


def _few_shot_fold(proto: CurrentModel, train: list[InteractionLog], target: list[InteractionLog],
                   names: list[str], model_name: str,
                   settings: AdaptSettings) -> tuple[list[AdaptScore], list[RunTotal], list[str]]:
    """Fit a fresh copy of ``proto`` on ``train`` (other grounds) and score it few-shot on ``target`` (module-level for dask)."""
    model = proto.clone().fit(train)
    return few_shot_scores(model, target, names, model_name=model_name, settings=settings)


def evaluate_few_shot(
    logs: Sequence[InteractionLog],
    model: CurrentModel | Mapping[str, CurrentModel],
    *,
    name: str = "model",
    settings: AdaptSettings | None = None,
    target_grounds: Sequence[str] | None = None,
    progress: bool = False,
    client: Any = None,
    out_dir: str | os.PathLike[str] | None = None,
) -> EvaluationResult:
    """The cross-ground few-shot table: train on the other grounds, adapt and test on the target.

    Parameters
    ----------
    logs : sequence of InteractionLog
        Runs with ``meta.ground_label`` set (at least two grounds).
    model : CurrentModel or mapping of str to CurrentModel
        The prototype (``clone()`` is fitted once per target ground), or several by name.
    name : str
        The model's name in the result (one model).
    settings : AdaptSettings, optional
        ``adapt_seconds``, the update and ``section_s``.
    target_grounds : sequence of str, optional
        Grounds to hold out in turn (default: every ground with at least 2 runs).
    progress, client, out_dir
        As :func:`~energy.evaluation.evaluate_adaptation`.

    Returns
    -------
    EvaluationResult
        Protocol ``"few-shot"`` (scores of protocol ``"few_shot"``).

    Raises
    ------
    InvalidParameterError
        Bad arguments.
    DataError
        Fewer than two grounds; a target ground that is missing or has fewer than 2 runs.
    """
    if out_dir is not None:
        check_evaluation_dir(out_dir, "few-shot")
    settings = AdaptSettings() if settings is None else settings
    if not isinstance(settings, AdaptSettings):
        raise InvalidParameterError(f"settings must be an AdaptSettings, got {settings!r:.80}")
    models = named_models(model, name)
    items = [trim_to_overlap(lg) for lg in check_runs(logs, labelled=True, what="the few-shot protocol")]
    check_client(client, "folds")
    names = run_names(items)
    grounds = list(dict.fromkeys(str(lg.meta.ground_label) for lg in items))
    if len(grounds) < 2:
        raise DataError(f"few-shot needs runs of at least 2 grounds (train on some, adapt on another), got {grounds!r}")
    counts = {g: sum(str(lg.meta.ground_label) == g for lg in items) for g in grounds}
    if target_grounds is None:
        targets = [g for g in grounds if counts[g] >= 2]
    else:
        if isinstance(target_grounds, (str, bytes)) or not isinstance(target_grounds, Sequence):
            raise InvalidParameterError(f"target_grounds must be a sequence of ground names, got {target_grounds!r:.80}")
        targets = [str(g) for g in target_grounds]
        for g in targets:
            if counts.get(g, 0) < 2:
                raise DataError(f"target ground {g!r} has {counts.get(g, 0)} runs; few-shot needs 2 "
                                f"(one to adapt on, one to test); grounds: {counts!r}")
    if not targets:
        raise DataError(f"no ground has 2 runs to adapt on one and test on another: {counts!r}")
    tasks = []
    for g in targets:
        idx = [i for i, lg in enumerate(items) if str(lg.meta.ground_label) == g]
        train = [lg for lg in items if str(lg.meta.ground_label) != g]
        tasks += [(_few_shot_fold, (proto, train, [items[i] for i in idx], [names[i] for i in idx], mname, settings))
                  for mname, proto in models.items()]
    return collect_adaptation(tasks, settings, [], client=client, progress=progress, description="few-shot grounds",
                              out_dir=out_dir)
