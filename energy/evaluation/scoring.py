"""Leave-one-run-out evaluation of drive-current models on interaction logs, per ground.

:func:`evaluate_current_models` fits every model on all runs of a ground but one and
scores it on the held-out run, for every run (``"per_ground"``), and optionally does the
same with one model over all grounds (``"ground_agnostic"``: train on every other run of
every ground). Each held-out run and side gets the whole-run error %, the section error
(``section_s`` sections, aggregated as ``sum |error| / sum truth``) and the RMSE; the
result (:class:`EvaluationResult`) summarises medians and 90th percentiles per ground and
over all grounds and writes ``evaluation.json`` and a markdown table.

Every per-run score of the library comes from :func:`score_run`, here: the folds of the
evaluation and :func:`score_current_model` (a model fitted beforehand, scored on given
runs) both use it, and both return an :class:`EvaluationResult`.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from terrawatt_base.checks import check_real, check_text
from terrawatt_base.dask_client import check_client, run_tasks
from terrawatt_base.errors import (
    DataError,
    InvalidParameterError,
    TerrawattWarning,
    UnknownNameError,
)

from ..battery import Battery
from ..logs import InteractionLog, run_names
from ..metrics import DEFAULT_SECTION_S, compare_currents
from ..models.base import CurrentModel, log_currents
from ..params import robot_params
from ..robot import RobotParams
from .results import (
    EVALUATION_VARIANTS,
    PREFIT_PROTOCOL,
    PREFIT_VARIANT,
    SIDES,
    EvaluationResult,
    RunScore,
    check_evaluation_dir,
    summarise_scores,
)
from .run_totals import RunTotal, ScoredRun, run_totals

__all__ = ["check_runs", "trim_to_overlap", "score_run", "score_current_model", "evaluate_current_models"]


def trim_to_overlap(log: InteractionLog) -> InteractionLog:
    """``log`` cut to the span covered by both its streams (itself when it already is)."""
    t0, t1 = log.overlap_s()
    if log.time_s[0] >= t0 and log.time_s[-1] <= t1:
        return log
    return log.slice(t0, float(np.nextafter(t1, np.inf)))


def score_run(
    model: CurrentModel,
    log: InteractionLog,
    *,
    variant: str,
    run: str,
    model_name: str,
    section_s: float = DEFAULT_SECTION_S,
    robot: str | RobotParams = "husky",
    battery: Battery | None = None,
) -> tuple[list[RunScore], list[RunTotal]]:
    """Score a fitted ``model`` on one run: one :class:`RunScore` per side (left, right) and the run's total.

    The one place where a run's predicted currents are compared with the logged ones
    (:func:`~energy.metrics.compare_currents`): whole-run error %, section error % and RMSE
    per side; and what the battery pays (:class:`~energy.evaluation.RunTotal`, protocol
    ``"loo"``, schedule ``variant``): the pack energy of both sides through ``battery``
    (default the ``robot``'s nominal voltage, ideal) and the total charge with the model's
    interval. The rows' ``fit_duration_s`` is NaN: the caller that fitted the model knows how long it took.

    Raises
    ------
    NotFittedError
        ``model`` is not fitted.
    DataError
        ``log`` has no measured currents.
    """
    measured = log_currents(log)  # a log without currents: DataError naming the missing topics
    fc = model.predict_distribution(log)
    pred = fc.mean_a
    truth = (measured[:, 0], measured[:, 1])
    rows = []
    for k, side in enumerate(SIDES):
        e = compare_currents(log.time_s, truth[k], pred[:, k], section_s)
        rows.append(RunScore(
            variant=variant, ground=str(log.meta.ground_label), run=run, model=model_name, side=side,
            duration_s=log.duration_s, charge_true_mah=e.charge_true_mah,
            charge_predicted_mah=e.charge_predicted_mah, whole_run_error_pct=e.whole_run_error_pct,
            section_error_pct=e.section_error_pct, rmse_a=e.rmse_a, fit_duration_s=math.nan,
        ))
    totals = run_totals(log, {"unadapted": (pred, fc)}, ScoredRun("loo", run, run, model_name, variant),
                        robot=robot_params(robot), battery=battery)
    return rows, totals


def _score_fold(
    logs: list[InteractionLog],
    variant: str,
    test: int,
    train: list[int],
    run: str,
    model_name: str,
    proto: CurrentModel,
    section_s: float,
) -> tuple[list[RunScore], list[RunTotal]]:
    """Fit a fresh copy of ``proto`` on ``logs[train]`` and score it on ``logs[test]``: one row per side, and the total.

    Module-level so that dask workers can unpickle it by reference.
    """
    t0 = time.perf_counter()
    model = proto.clone().fit([logs[j] for j in train])
    fit_s = time.perf_counter() - t0
    rows, totals = score_run(model, logs[test], variant=variant, run=run, model_name=model_name, section_s=section_s)
    return [dataclasses.replace(row, fit_duration_s=fit_s) for row in rows], totals


def score_current_model(
    model: CurrentModel,
    logs: Sequence[InteractionLog],
    *,
    name: str = "model",
    section_s: float = DEFAULT_SECTION_S,
) -> EvaluationResult:
    """Score a model fitted beforehand (e.g. a loaded one) on every run of ``logs``.

    Each run is scored as it is (not trimmed): one :class:`RunScore` per run and side, of
    variant ``"prefit"`` with a NaN ``fit_duration_s``, and their summaries per ground and
    over all grounds. Runs are named as in :func:`run_names`. The result's protocol is
    ``"prefit"``, its label ``name``.

    Parameters
    ----------
    model : CurrentModel
        A fitted model.
    logs : sequence of InteractionLog
        Runs to score the model on (``meta.ground_label`` may be None).
    name : str
        The model's name in the result.
    section_s : float
        Section length of the section error (s, > 0).

    Returns
    -------
    EvaluationResult

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel; empty ``logs`` or not InteractionLogs; a bad ``name`` or
        ``section_s``.
    NotFittedError
        ``model`` is not fitted.
    """
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a CurrentModel, got {model!r:.80}")
    check_text("name", name)
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    items = check_runs(logs)
    names = run_names(items)
    scores: list[RunScore] = []
    totals: list[RunTotal] = []
    for run, log in zip(names, items):
        rows, run_rows = score_run(model, log, variant=PREFIT_VARIANT, run=run, model_name=name, section_s=section_s)
        scores += rows
        totals += run_rows
    grounds = list(dict.fromkeys(str(log.meta.ground_label) for log in items))
    variants = (PREFIT_VARIANT,)
    summary = summarise_scores(scores, variants, grounds, (name,))
    return EvaluationResult(tuple(scores), summary, protocol=PREFIT_PROTOCOL, totals=tuple(totals), models=(name,),
                            variants=variants, section_s=float(section_s), logs=tuple(items), label=name, model=model)


def check_runs(logs: Any, *, labelled: bool = False, what: str = "the evaluation") -> list[InteractionLog]:
    """``logs`` as a list: a non-empty sequence of InteractionLogs (one log alone is refused: the
    protocols compare runs); with ``labelled``, each must carry ``meta.ground_label``.

    Raises
    ------
    InvalidParameterError
        Not a non-empty sequence of InteractionLogs.
    DataError
        ``labelled`` and a log without a ground label.
    """
    if isinstance(logs, InteractionLog) or isinstance(logs, (str, bytes)) or not isinstance(logs, Sequence):
        raise InvalidParameterError(f"logs must be a sequence of InteractionLog, got {logs!r:.80}")
    items = list(logs)
    if not items:
        raise InvalidParameterError("logs must hold at least one InteractionLog, got none")
    for i, log in enumerate(items):
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"logs[{i}] must be an InteractionLog, got {log!r:.80}")
        if labelled and log.meta.ground_label is None:
            raise DataError(f"logs[{i}] ({log.meta.source!r}) has no meta.ground_label; {what} groups runs by ground")
    return items


def evaluate_current_models(
    logs: Sequence[InteractionLog],
    models: Mapping[str, CurrentModel],
    *,
    variants: Sequence[str] = EVALUATION_VARIANTS,
    section_s: float = DEFAULT_SECTION_S,
    progress: bool = False,
    client: Any = None,
    out_dir: str | os.PathLike[str] | None = None,
) -> EvaluationResult:
    """Leave-one-run-out evaluation of current models, per ground and over all grounds.

    Each log is first cut to the span covered by both its streams. For ``"per_ground"``,
    for every ground with at least two runs and every run of it, a fresh copy of each model
    (``model.clone()``: same parameters and seed, unfitted) is fitted on the ground's other
    runs and scored on the run. ``"ground_agnostic"`` does the same with the training set
    made of every other run of every ground.

    With a dask ``client``, every (fold, model) pair is one task on the cluster: the
    trimmed logs are sent to every worker once (:func:`~terrawatt_base.dask_client.run_tasks`),
    each task fits, predicts and scores one model on one fold, and the scores are put back in
    the order of the serial run, so the result does not depend on which task finishes first.

    Parameters
    ----------
    logs : sequence of InteractionLog
        Runs, each with ``meta.ground_label`` set.
    models : mapping of str to CurrentModel
        Named prototypes (not modified).
    variants : sequence of str
        Subset of :data:`EVALUATION_VARIANTS`.
    section_s : float
        Section length of the section error (s).
    progress : bool
        Show a tqdm bar over the (fold, model) tasks.
    client : distributed.Client or None
        ``None`` (default): fit and score the folds here, one after another. A
        ``distributed.Client``: run them as tasks on its cluster (needs the
        ``distributed`` extra; every worker must be able to import terrawatt). An
        exception raised in a task is raised here, and the remaining tasks are cancelled.
    out_dir : str or os.PathLike, optional
        Folder to write ``evaluation.json``, ``evaluation.md`` and the reliability figure into
        (:meth:`EvaluationResult.write`); checked before any model is fitted.

    Returns
    -------
    EvaluationResult

    Raises
    ------
    InvalidParameterError
        Empty ``logs`` or ``models``; a model that is not a CurrentModel; a ``client``
        that is neither ``None`` nor a ``distributed.Client``; a bad ``section_s``; an
        ``out_dir`` that cannot be written (a file, or under a file).
    OptionalDependencyError
        A ``client`` is given but dask.distributed is not installed.
    UnknownNameError
        An unknown variant.
    DataError
        A log without ``meta.ground_label``; fewer than two runs in total.

    Warns
    -----
    TerrawattWarning
        A ground with a single run is left out of the per-ground variant (it is listed in
        ``EvaluationResult.skipped``).

    Notes
    -----
    On a cluster the scores equal the serial ones for models whose fit and predict do not
    depend on the thread count. Torch models (and BLAS-backed fits) can differ in the last
    bits when a worker runs another number of threads than this process: dask's nanny
    sets ``OMP_NUM_THREADS=1`` (and ``MKL_NUM_THREADS``, ``OPENBLAS_NUM_THREADS``) before
    it starts a worker process (``distributed.nanny.pre-spawn-environ``; a value already
    set in the nanny's environment wins), so torch there uses one thread. Pin the count
    on both sides (``VibrationCurrentEstimator(..., n_threads=1)``) for identical results
    on one machine. ``fit_duration_s`` is measured on the worker.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        from energy import LinearCurrentModel, read_borealtc
        res = evaluate_current_models(read_borealtc("borealtc"), {"linear": LinearCurrentModel()})
        print(res.summary())

    The same folds on a local dask cluster of two worker processes::

        from distributed import Client, LocalCluster
        with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
            res = evaluate_current_models(logs, {"linear": LinearCurrentModel()}, client=client)
    """
    if out_dir is not None:
        check_evaluation_dir(out_dir)  # before the work, not after it
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    items = check_runs(logs, labelled=True)
    if not models:
        raise InvalidParameterError("models must name at least one CurrentModel, got none")
    for name, m in models.items():
        if not isinstance(m, CurrentModel):
            raise InvalidParameterError(f"models[{name!r}] must be a CurrentModel, got {m!r:.80}")
    chosen = tuple(variants)
    for v in chosen:
        if v not in EVALUATION_VARIANTS:
            raise UnknownNameError(f"variant {v!r} is unknown; expected names from {EVALUATION_VARIANTS!r}")
    check_client(client, "folds")
    if len(items) < 2:
        raise DataError(f"leave-one-run-out needs at least 2 runs, got {len(items)}")
    items = [trim_to_overlap(log) for log in items]
    names = run_names(items)
    grounds = list(dict.fromkeys(log.meta.ground_label for log in items))
    skipped: list[str] = []
    folds: list[tuple[str, int, list[int]]] = []  # (variant, test index, train indices)
    if "per_ground" in chosen:
        for g in grounds:
            idx = [i for i, log in enumerate(items) if log.meta.ground_label == g]
            if len(idx) < 2:
                msg = f"ground {g!r} has {len(idx)} run; per-ground leave-one-run-out needs 2"
                warnings.warn(msg, TerrawattWarning, stacklevel=2)
                skipped.append(msg)
                continue
            folds += [("per_ground", i, [j for j in idx if j != i]) for i in idx]
    if "ground_agnostic" in chosen:
        folds += [("ground_agnostic", i, [j for j in range(len(items)) if j != i]) for i in range(len(items))]

    # every (fold, model) pair one task; the trimmed logs sent to every worker once
    tasks = [(_score_fold, (variant, test, train, names[test], mname, proto, section_s))
             for variant, test, train in folds for mname, proto in models.items()]
    scores: list[RunScore] = []
    totals: list[RunTotal] = []
    for rows, run_rows in run_tasks(tasks, client=client, shared=(items,), progress=progress,
                                    description="evaluation tasks"):
        scores += rows
        totals += run_rows
    summary = summarise_scores(scores, chosen, grounds, tuple(models))
    result = EvaluationResult(tuple(scores), summary, totals=tuple(totals), skipped=tuple(skipped),
                              models=tuple(models), variants=chosen, section_s=float(section_s))
    if out_dir is not None:
        result.write(out_dir)
    return result
