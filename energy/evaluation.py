"""Leave-one-run-out evaluation of drive-current models on interaction logs, per ground.

:func:`evaluate_current_models` fits every model on all runs of a ground but one and
scores it on the held-out run, for every run (``"per_ground"``), and optionally does the
same with one model over all grounds (``"ground_agnostic"``: train on every other run of
every ground). Each held-out run and side gets the whole-run error %, the section error
(``section_s`` sections, aggregated as ``sum |error| / sum truth``) and the RMSE; the
result (:class:`EvaluationResult`) summarises medians and 90th percentiles per ground and
over all grounds and writes ``evaluation.json`` and a markdown table.
"""

from __future__ import annotations

import json
import math
import os
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain.atomic import write_text_atomic
from terrain.errors import (
    DataError,
    InvalidParameterError,
    OptionalDependencyError,
    TerrawattWarning,
    UnknownNameError,
)

from .models.base import CurrentModel
from .logs import InteractionLog
from .metrics import DEFAULT_SECTION_S, compare_currents

__all__ = [
    "EVALUATION_VARIANTS",
    "EVALUATION_FORMAT_VERSION",
    "RunScore",
    "ScoreSummary",
    "EvaluationResult",
    "evaluate_current_models",
]

#: Evaluation variants: one model per ground, or one model over all grounds.
EVALUATION_VARIANTS = ("per_ground", "ground_agnostic")
#: Version of the ``evaluation.json`` layout.
EVALUATION_FORMAT_VERSION = 1
_ALL = "all"
_SIDES = ("left", "right")


@dataclass(frozen=True)
class RunScore:
    """Scores of one model on one held-out run and one drive side."""

    variant: str
    ground: str
    run: str
    model: str
    side: str
    duration_s: float
    charge_true_mah: float
    charge_predicted_mah: float
    whole_run_error_pct: float
    section_error_pct: float
    rmse_a: float
    fit_duration_s: float

    def __post_init__(self) -> None:
        if self.variant not in EVALUATION_VARIANTS:
            raise UnknownNameError(f"RunScore.variant must be one of {EVALUATION_VARIANTS!r}, got {self.variant!r}")
        if self.side not in _SIDES:
            raise UnknownNameError(f"RunScore.side must be one of {_SIDES!r}, got {self.side!r}")


@dataclass(frozen=True)
class ScoreSummary:
    """Medians and 90th percentiles over the (run, side) scores of one model on one ground.

    ``ground`` is ``"all"`` for the pool over every ground. NaN scores (a side with zero
    true charge) are left out and counted in ``n_undefined``.
    """

    variant: str
    ground: str
    model: str
    n_runs: int
    n_values: int
    n_undefined: int
    whole_run_median_pct: float
    whole_run_p90_pct: float
    section_median_pct: float
    section_p90_pct: float
    rmse_median_a: float
    rmse_p90_a: float
    fit_duration_median_s: float


def _stat(values: list[float], q: float) -> float:
    arr = np.asarray(values, dtype=np.float64)
    arr = arr[np.isfinite(arr)]
    return float(np.percentile(arr, q)) if arr.size else math.nan


def _summarise(variant: str, ground: str, model: str, scores: list[RunScore]) -> ScoreSummary:
    whole = [s.whole_run_error_pct for s in scores]
    sec = [s.section_error_pct for s in scores]
    rmse = [s.rmse_a for s in scores]
    return ScoreSummary(
        variant=variant, ground=ground, model=model,
        n_runs=len({s.run for s in scores}), n_values=len(scores),
        n_undefined=int(sum(not math.isfinite(w) for w in whole)),
        whole_run_median_pct=_stat(whole, 50), whole_run_p90_pct=_stat(whole, 90),
        section_median_pct=_stat(sec, 50), section_p90_pct=_stat(sec, 90),
        rmse_median_a=_stat(rmse, 50), rmse_p90_a=_stat(rmse, 90),
        fit_duration_median_s=_stat([s.fit_duration_s for s in scores], 50),
    )


def _plain(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


@dataclass(frozen=True)
class EvaluationResult:
    """All scores of :func:`evaluate_current_models` and their summaries.

    Attributes
    ----------
    runs : tuple of RunScore
        One per (variant, held-out run, model, side).
    summary : tuple of ScoreSummary
        One per (variant, ground or ``"all"``, model).
    models : tuple of str
        Model names, in the order given.
    variants : tuple of str
    section_s : float
    skipped : tuple of str
        Grounds left out of the per-ground variant and why.
    """

    runs: tuple[RunScore, ...]
    summary: tuple[ScoreSummary, ...]
    models: tuple[str, ...]
    variants: tuple[str, ...]
    section_s: float
    skipped: tuple[str, ...] = ()

    def summary_for(self, variant: str, ground: str, model: str) -> ScoreSummary:
        """The summary row of one variant, ground (or ``"all"``) and model.

        Raises
        ------
        UnknownNameError
            No such row.
        """
        for s in self.summary:
            if (s.variant, s.ground, s.model) == (variant, ground, model):
                return s
        raise UnknownNameError(
            f"no summary for variant={variant!r}, ground={ground!r}, model={model!r}; rows exist for "
            f"{sorted({(s.variant, s.ground, s.model) for s in self.summary})!r}"
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form (NaN becomes ``None``), as written to ``evaluation.json``."""
        return _plain({
            "format": "terrawatt-evaluation",
            "format_version": EVALUATION_FORMAT_VERSION,
            "section_s": self.section_s,
            "models": list(self.models),
            "variants": list(self.variants),
            "skipped": list(self.skipped),
            "summary": [asdict(s) for s in self.summary],
            "runs": [asdict(r) for r in self.runs],
        })

    def write_json(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_dict` as JSON, atomically."""
        return write_text_atomic(path, json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n")

    def to_markdown(self) -> str:
        """A markdown table of the summary: per variant, ground and model."""
        def f(x: float, nd: int = 1) -> str:
            return "–" if not math.isfinite(x) else f"{x:.{nd}f}"

        lines = [
            f"| variant | ground | model | runs | whole-run median % | whole-run p90 % | "
            f"{self.section_s:g} s sections median % | sections p90 % | RMSE median A |",
            "|---|---|---|---:|---:|---:|---:|---:|---:|",
        ]
        for s in self.summary:
            lines.append(
                f"| {s.variant} | {s.ground} | {s.model} | {s.n_runs} | {f(s.whole_run_median_pct)} | "
                f"{f(s.whole_run_p90_pct)} | {f(s.section_median_pct)} | {f(s.section_p90_pct)} | {f(s.rmse_median_a, 2)} |"
            )
        if self.skipped:
            lines.append("")
            lines.extend(f"Skipped: {s}" for s in self.skipped)
        return "\n".join(lines) + "\n"

    def write_markdown(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_markdown`, atomically."""
        return write_text_atomic(path, self.to_markdown())


def _run_names(logs: list[InteractionLog]) -> list[str]:
    names = []
    for log in logs:
        stem = Path(log.meta.source).stem if log.meta.source else "run"
        names.append(f"{log.meta.ground_label}/{stem}")
    seen: dict[str, int] = {}
    out = []
    for n in names:
        k = seen.get(n, 0)
        seen[n] = k + 1
        out.append(n if names.count(n) == 1 else f"{n}#{k}")
    return out


def _trim(log: InteractionLog) -> InteractionLog:
    t0, t1 = log.overlap_s()
    if log.time_s[0] >= t0 and log.time_s[-1] <= t1:
        return log
    return log.slice(t0, float(np.nextafter(t1, np.inf)))


def _score_fold(
    variant: str,
    run: str,
    log: InteractionLog,
    train_logs: list[InteractionLog],
    model_name: str,
    proto: CurrentModel,
    section_s: float,
) -> list[RunScore]:
    """Fit a fresh copy of ``proto`` on ``train_logs`` and score it on ``log``: one row per side.

    Module-level so that dask workers can unpickle it by reference.
    """
    t0 = time.perf_counter()
    model = proto.clone().fit(train_logs)
    fit_s = time.perf_counter() - t0
    pred = model.predict(log)
    truth = (log.current_left_a, log.current_right_a)
    rows = []
    for k, side in enumerate(_SIDES):
        e = compare_currents(log.time_s, truth[k], pred[:, k], section_s)
        rows.append(RunScore(
            variant=variant, ground=str(log.meta.ground_label), run=run, model=model_name, side=side,
            duration_s=log.duration_s, charge_true_mah=e.charge_true_mah,
            charge_predicted_mah=e.charge_predicted_mah, whole_run_error_pct=e.whole_run_error_pct,
            section_error_pct=e.section_error_pct, rmse_a=e.rmse_a, fit_duration_s=fit_s,
        ))
    return rows


def _distributed_client_type() -> type:
    """``distributed.Client``, imported only when a client is given (the extra is optional)."""
    try:
        from distributed import Client
    except ImportError as exc:
        raise OptionalDependencyError(
            "evaluating on a cluster needs dask.distributed; install it with: pip install 'terrawatt[distributed]'"
        ) from exc
    return Client


def _score_on_cluster(
    client: Any,
    items: list[InteractionLog],
    names: list[str],
    folds: list[tuple[str, int, list[int]]],
    models: Mapping[str, CurrentModel],
    section_s: float,
    progress: bool,
) -> list[RunScore]:
    """Every (fold, model) pair as one task on ``client``; rows in the serial order."""
    from distributed import as_completed
    from tqdm.auto import tqdm

    scattered = client.scatter(items, broadcast=True, hash=False)
    futures = [
        client.submit(
            _score_fold, variant, names[test], scattered[test], [scattered[j] for j in train], mname, proto,
            section_s, pure=False,
        )
        for variant, test, train in folds
        for mname, proto in models.items()
    ]
    position = {f.key: i for i, f in enumerate(futures)}
    rows: list[list[RunScore]] = [[] for _ in futures]
    try:
        with tqdm(total=len(futures), desc="evaluation tasks", disable=not progress) as bar:
            for fut in as_completed(futures):
                rows[position[fut.key]] = fut.result()  # re-raises a task's exception here
                bar.update()
    except BaseException:
        client.cancel(futures + scattered)  # drop the tasks still queued or running
        raise
    return [row for task_rows in rows for row in task_rows]


def evaluate_current_models(
    logs: Sequence[InteractionLog],
    models: Mapping[str, CurrentModel],
    *,
    variants: Sequence[str] = EVALUATION_VARIANTS,
    section_s: float = DEFAULT_SECTION_S,
    progress: bool = False,
    client: Any = None,
) -> EvaluationResult:
    """Leave-one-run-out evaluation of current models, per ground and over all grounds.

    Each log is first cut to the span covered by both its streams. For ``"per_ground"``,
    for every ground with at least two runs and every run of it, a fresh copy of each model
    (``model.clone()``: same parameters and seed, unfitted) is fitted on the ground's other
    runs and scored on the run. ``"ground_agnostic"`` does the same with the training set
    made of every other run of every ground.

    With a dask ``client``, every (fold, model) pair is one task on the cluster: the
    trimmed logs are scattered to every worker once, each task fits, predicts and scores
    one model on one fold, and the scores are put back in the order of the serial run, so
    the result does not depend on which task finishes first.

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
        Show a tqdm bar over the folds (over the completed tasks with a ``client``).
    client : distributed.Client or None
        ``None`` (default): fit and score the folds here, one after another. A
        ``distributed.Client``: run them as tasks on its cluster (needs the
        ``distributed`` extra; every worker must be able to import terrawatt). An
        exception raised in a task is raised here, and the remaining tasks are cancelled.

    Returns
    -------
    EvaluationResult

    Raises
    ------
    InvalidParameterError
        Empty ``logs`` or ``models``; a model that is not a CurrentModel; a ``client``
        that is neither ``None`` nor a ``distributed.Client``.
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
        print(res.to_markdown())

    The same folds on a local dask cluster of two worker processes::

        from distributed import Client, LocalCluster
        with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
            res = evaluate_current_models(logs, {"linear": LinearCurrentModel()}, client=client)
    """
    items = list(logs)
    if not items:
        raise InvalidParameterError("logs must hold at least one InteractionLog, got none")
    for i, log in enumerate(items):
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"logs[{i}] must be an InteractionLog, got {log!r:.80}")
        if log.meta.ground_label is None:
            raise DataError(f"logs[{i}] ({log.meta.source!r}) has no meta.ground_label; the evaluation groups runs by ground")
    if not models:
        raise InvalidParameterError("models must name at least one CurrentModel, got none")
    for name, m in models.items():
        if not isinstance(m, CurrentModel):
            raise InvalidParameterError(f"models[{name!r}] must be a CurrentModel, got {m!r:.80}")
    chosen = tuple(variants)
    for v in chosen:
        if v not in EVALUATION_VARIANTS:
            raise UnknownNameError(f"variant {v!r} is unknown; expected names from {EVALUATION_VARIANTS!r}")
    if client is not None and not isinstance(client, _distributed_client_type()):
        raise InvalidParameterError(
            f"client must be None (run the folds here, one after another) or a distributed.Client, got {client!r:.80}"
        )
    if len(items) < 2:
        raise DataError(f"leave-one-run-out needs at least 2 runs, got {len(items)}")
    items = [_trim(log) for log in items]
    names = _run_names(items)
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

    scores: list[RunScore] = []
    if client is not None:
        scores = _score_on_cluster(client, items, names, folds, models, section_s, progress)
    else:
        from tqdm.auto import tqdm

        for variant, test, train in tqdm(folds, desc="evaluation folds", disable=not progress):
            train_logs = [items[j] for j in train]
            for mname, proto in models.items():
                scores += _score_fold(variant, names[test], items[test], train_logs, mname, proto, section_s)
    summary: list[ScoreSummary] = []
    for variant in chosen:
        for g in grounds + [_ALL]:
            for mname in models:
                rows = [s for s in scores if s.variant == variant and s.model == mname and (g == _ALL or s.ground == g)]
                if rows:
                    summary.append(_summarise(variant, g, mname, rows))
    return EvaluationResult(tuple(scores), tuple(summary), tuple(models), chosen, float(section_s), tuple(skipped))
