"""Scores of drive-current models on held-out runs: :class:`RunScore`, :class:`ScoreSummary`, :class:`EvaluationResult`."""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import check_output_path, json_finite, write_text_atomic
from terrawatt_base.formats import result_document, write_result_json
from terrawatt_base.errors import UnknownNameError

from .run_totals import TOTALS_HEADING, RunTotal, plot_totals_reliability, summarise_totals, totals_markdown

__all__ = [
    "EVALUATION_VARIANTS",
    "PREFIT_VARIANT",
    "SCORE_VARIANTS",
    "EVALUATION_FORMAT_VERSION",
    "EVALUATION_FILES",
    "SIDES",
    "RunScore",
    "ScoreSummary",
    "EvaluationResult",
    "summarise_scores",
    "check_evaluation_dir",
]

#: Evaluation variants: one model per ground, or one model over all grounds.
EVALUATION_VARIANTS = ("per_ground", "ground_agnostic")
#: Variant of the scores of a model fitted beforehand (:func:`~energy.evaluation.score_current_model`).
PREFIT_VARIANT = "prefit"
#: Every variant a :class:`RunScore` may carry.
SCORE_VARIANTS = (*EVALUATION_VARIANTS, PREFIT_VARIANT)
#: Version of the ``evaluation.json`` layout (2: each run's pack energy, total charge and interval
#: coverage, ``totals`` and ``total_summary``).
EVALUATION_FORMAT_VERSION = 2
#: Files :meth:`EvaluationResult.write` writes into its folder.
EVALUATION_FILES = ("evaluation.json", "evaluation.md")
#: Drive sides, in the column order of a model's predictions.
SIDES = ("left", "right")
_ALL = "all"


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
        if self.variant not in SCORE_VARIANTS:
            raise UnknownNameError(f"RunScore.variant must be one of {SCORE_VARIANTS!r}, got {self.variant!r}")
        if self.side not in SIDES:
            raise UnknownNameError(f"RunScore.side must be one of {SIDES!r}, got {self.side!r}")


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
    """The summary of one variant, ground and model over ``scores`` (already selected)."""
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
    totals : tuple of RunTotal
        What the battery pays: per held-out run, the pack energy and total charge of both
        sides with the model's interval (protocol ``"loo"``, schedule the variant);
        summarised by :meth:`total_summary`.
    """

    runs: tuple[RunScore, ...]
    summary: tuple[ScoreSummary, ...]
    models: tuple[str, ...]
    variants: tuple[str, ...]
    section_s: float
    skipped: tuple[str, ...] = ()
    totals: tuple[RunTotal, ...] = ()

    def total_summary(self) -> list[dict[str, Any]]:
        """Per variant, ground (then all) and model: pack energy and total charge errors (median, p90 %)
        and the coverage of the 50 / 80 / 95 % intervals (:func:`~energy.evaluation.run_totals.summarise_totals`)."""
        return summarise_totals(self.totals)

    def plot_reliability(self, ax: Any = None) -> Any:
        """Observed against nominal coverage of the total-charge intervals per variant and ground."""
        return plot_totals_reliability(self.totals, ax, title="held-out total charge (both sides)")

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
        return json_finite(result_document("evaluation", EVALUATION_FORMAT_VERSION, {
            "section_s": self.section_s,
            "models": list(self.models),
            "variants": list(self.variants),
            "skipped": list(self.skipped),
            "total_summary": self.total_summary(),
            "summary": [asdict(s) for s in self.summary],
            "totals": [t.to_dict() for t in self.totals],
            "runs": [asdict(r) for r in self.runs],
        }))

    def write_json(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_dict` as JSON, atomically (:func:`terrawatt_base.formats.write_result_json`)."""
        return write_result_json(path, self.to_dict())

    def to_markdown(self) -> str:
        """Markdown tables: what the battery pays (both sides through the pack, total charge and its
        interval's coverage) first, then per side: per variant, ground and model."""
        def f(x: float, nd: int = 1) -> str:
            return "–" if not math.isfinite(x) else f"{x:.{nd}f}"

        lines = []
        if self.totals:
            lines += [TOTALS_HEADING, "", totals_markdown(self.total_summary()), "Per side (charge of each motor channel):",
                      ""]
        lines += [
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

    def write(self, out_dir: str | os.PathLike[str]) -> tuple[Path, Path]:
        """Write ``evaluation.json`` and ``evaluation.md`` into ``out_dir`` (created if missing).

        Raises
        ------
        InvalidParameterError
            See :func:`check_evaluation_dir`.
        """
        folder = check_evaluation_dir(out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        json_name, md_name = EVALUATION_FILES
        return self.write_json(folder / json_name), self.write_markdown(folder / md_name)



def summarise_scores(scores: list[RunScore], variants: tuple[str, ...], grounds: list[str],
                     models: tuple[str, ...]) -> tuple[ScoreSummary, ...]:
    """One :class:`ScoreSummary` per variant, ground (then ``"all"``) and model that has scores."""
    summary: list[ScoreSummary] = []
    for variant in variants:
        for g in [*grounds, _ALL]:
            for mname in models:
                rows = [s for s in scores if s.variant == variant and s.model == mname and (g == _ALL or s.ground == g)]
                if rows:
                    summary.append(_summarise(variant, g, mname, rows))
    return tuple(summary)


def check_evaluation_dir(out_dir: str | os.PathLike[str], name: str = "out_dir") -> Path:
    """Check, before any work, that :meth:`EvaluationResult.write` can write into ``out_dir``.

    Raises
    ------
    InvalidParameterError
        ``out_dir`` is a file, lies under a file, or one of :data:`EVALUATION_FILES` in it is
        a directory.
    """
    folder = check_output_path(out_dir, name, directory=True)
    for file in EVALUATION_FILES:
        check_output_path(folder / file, name)
    return folder
