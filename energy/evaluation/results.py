"""Scores of drive-current models on runs: :class:`RunScore`, :class:`ScoreRow`, and the answer of every protocol,
:class:`EvaluationResult` (its summary, JSON, files and figures)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from terrawatt_base.answer import fmt_fixed, markdown_table, write_answer
from terrawatt_base.atomic import check_output_path, json_finite, save_figure, write_text_atomic
from terrawatt_base.checks import check_bool, check_choice
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from terrawatt_base.figure_file import FIGURE_ERRORS
from terrawatt_base.formats import result_document, write_result_json
from terrawatt_base.plot_target import check_ax, check_plot_target

from ..logs import InteractionLog
from ..models.base import CurrentModel
from ..plots import plot_current_estimate, plot_vibration_spectra
from ..prediction import RunPrediction
from .adapt_results import ADAPT_FILES, ADAPT_FORMAT_VERSION, AdaptRow, AdaptScore, adapt_table, finite_percentile
from .run_totals import TOTALS_HEADING, RunTotal, plot_totals_reliability, summarise_totals, totals_markdown

__all__ = [
    "EVALUATION_PROTOCOLS",
    "PREFIT_PROTOCOL",
    "RESULT_PROTOCOLS",
    "PREDICTIONS_FILE",
    "PREDICTIONS_FORMAT_VERSION",
    "FIGURES_FOLDER",
    "SPECTRA_FILE",
    "RELIABILITY_FILE",
    "EVALUATION_VARIANTS",
    "PREFIT_VARIANT",
    "SCORE_VARIANTS",
    "EVALUATION_FORMAT_VERSION",
    "EVALUATION_FILES",
    "SIDES",
    "RunScore",
    "ScoreRow",
    "EvaluationResult",
    "summarise_scores",
    "evaluation_files",
    "check_evaluation_dir",
]

#: The protocols: leave one run out, adapt on each held-out run's first seconds, few shots on a ground left out.
EVALUATION_PROTOCOLS = ("loo", "adapt", "few-shot")
#: The protocol of a model fitted beforehand applied to logs (``terrawatt predict``): scored where every log has
#: measured currents, else predicted only.
PREFIT_PROTOCOL = "prefit"
#: Every protocol of an :class:`EvaluationResult`.
RESULT_PROTOCOLS = (*EVALUATION_PROTOCOLS, PREFIT_PROTOCOL)
_ADAPT = ("adapt", "few-shot")
#: The file a result of protocol ``"prefit"`` writes, and the folder of its figures.
PREDICTIONS_FILE = "predictions.json"
FIGURES_FOLDER = "plots"
#: Format version of an unscored ``predictions.json`` (``terrawatt-predictions``; a scored one is an evaluation).
PREDICTIONS_FORMAT_VERSION = 1
#: The figure of a leave-one-run-out result with its logs: their vibration spectra per ground.
SPECTRA_FILE = "spectra.png"
#: The reliability figure of every protocol: observed against nominal coverage of the held-out total charge's
#: intervals per protocol, ground and forecast.
RELIABILITY_FILE = "reliability.png"

#: Evaluation variants: one model per ground, or one model over all grounds.
EVALUATION_VARIANTS = ("per_ground", "ground_agnostic")
#: Variant of the scores of a model fitted beforehand (:func:`~energy.evaluation.score_current_model`, protocol
#: :data:`PREFIT_PROTOCOL`).
PREFIT_VARIANT = "prefit"
#: Every variant a :class:`RunScore` may carry.
SCORE_VARIANTS = (*EVALUATION_VARIANTS, PREFIT_VARIANT)
#: Version of the ``evaluation.json`` layout (2: each run's pack energy, total charge and interval
#: coverage, ``totals`` and ``total_summary``).
EVALUATION_FORMAT_VERSION = 2
#: The JSON and markdown files :meth:`EvaluationResult.write` writes leaving one run out.
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
class ScoreRow:
    """A row of the leave-one-run-out table: medians and 90th percentiles over the (run, side) scores of one model on one ground.

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


def _summarise(variant: str, ground: str, model: str, scores: list[RunScore]) -> ScoreRow:
    """The summary of one variant, ground and model over ``scores`` (already selected)."""
    whole = [s.whole_run_error_pct for s in scores]
    sec = [s.section_error_pct for s in scores]
    rmse = [s.rmse_a for s in scores]
    return ScoreRow(
        variant=variant, ground=ground, model=model,
        n_runs=len({s.run for s in scores}), n_values=len(scores),
        n_undefined=int(sum(not math.isfinite(w) for w in whole)),
        whole_run_median_pct=finite_percentile(whole, 50), whole_run_p90_pct=finite_percentile(whole, 90),
        section_median_pct=finite_percentile(sec, 50), section_p90_pct=finite_percentile(sec, 90),
        rmse_median_a=finite_percentile(rmse, 50), rmse_p90_a=finite_percentile(rmse, 90),
        fit_duration_median_s=finite_percentile([s.fit_duration_s for s in scores], 50),
    )


@dataclass(frozen=True)
class EvaluationResult:
    """Current models scored on runs by one protocol: the answer of ``terrawatt evaluate`` and ``terrawatt predict``.

    Made by :func:`~energy.evaluation.evaluate_kinds` (with the header: the kinds, the logs, the
    wall time), :func:`evaluate_current_models`, :func:`~energy.evaluation.evaluate_adaptation`,
    :func:`~energy.evaluation.evaluate_few_shot`, and for a model fitted beforehand (protocol
    ``"prefit"``) :func:`~energy.evaluation.score_current_model` and :func:`~energy.evaluation.predict_logs`
    (which, when some log has no measured currents, predicts instead: :attr:`scored` false).
    :meth:`summary` is the text the command prints, :meth:`to_dict` the versioned JSON
    (``evaluation.json`` leaving one run out, ``adapt.json`` for the adapt protocols, ``predictions.json``
    for ``"prefit"``), :meth:`write` writes :func:`evaluation_files` and the figures, :meth:`plot` draws the
    reliability of the total charge's intervals.

    Attributes
    ----------
    runs : tuple of RunScore or of AdaptScore
        One per (variant, held-out run, model, side); with the adapt protocols one per (scored run,
        run adapted on, model, schedule, side).
    rows : tuple of ScoreRow or of AdaptRow
        The medians and 90th percentiles: one per (variant, ground or ``"all"``, model); with the adapt
        protocols one per (ground or ``"all"``, model, schedule). :meth:`row_for` finds one.
    protocol : str
        One of :data:`RESULT_PROTOCOLS`: ``"loo"`` (leave one run out), ``"adapt"``, ``"few-shot"`` or
        ``"prefit"`` (a model fitted beforehand, variant ``"prefit"``).
    totals : tuple of RunTotal
        What the battery pays: per scored run (schedule, variant), the pack energy and total charge of
        both sides with the forecast's interval (:mod:`~energy.evaluation.run_totals`); summarised by
        :meth:`total_summary`.
    skipped : tuple of str
        Grounds or runs left out and why.
    models, variants : tuple of str
        ``"loo"``, ``"prefit"``: the model names, in the order given, and the variants.
    section_s : float
        ``"loo"``, ``"prefit"``: the section length of the section error (s); the adapt protocols hold theirs in
        ``settings``.
    settings : dict
        The adapt protocols' settings (method, prior, threshold, minimum remainder...).
    kinds : tuple of str
        The header: the model kinds evaluated (:func:`~energy.evaluation.evaluate_kinds`).
    logs : tuple of InteractionLog
        The header: the runs (their vibration spectra are drawn leaving one run out).
    duration_s : float
        The header: wall time of the evaluation, s (NaN without a header).
    label : str
        ``"prefit"``: how the files name the model (e.g. its file; its last path part names it in the scores).
    model : CurrentModel or None
        ``"prefit"``: the fitted model (its figures predict the logs again).
    predictions : tuple of RunPrediction
        ``"prefit"`` when some log has no measured currents: the predictions per run
        (:func:`energy.prediction.predict_runs`), and no scores.
    """

    runs: tuple[RunScore, ...] | tuple[AdaptScore, ...]
    rows: tuple[ScoreRow, ...] | tuple[AdaptRow, ...]
    protocol: str = "loo"
    totals: tuple[RunTotal, ...] = ()
    skipped: tuple[str, ...] = ()
    models: tuple[str, ...] = ()
    variants: tuple[str, ...] = ()
    section_s: float = math.nan
    settings: dict[str, Any] = field(default_factory=dict)
    kinds: tuple[str, ...] = ()
    logs: tuple[InteractionLog, ...] = ()
    duration_s: float = math.nan
    label: str = ""
    model: CurrentModel | None = None
    predictions: tuple[RunPrediction, ...] = ()

    def __post_init__(self) -> None:
        check_choice("protocol", self.protocol, RESULT_PROTOCOLS)
        kind = AdaptScore if self.protocol in _ADAPT else RunScore
        if not all(isinstance(r, kind) for r in self.runs):
            raise InvalidParameterError(f"EvaluationResult.runs of protocol {self.protocol!r} must be "
                                        f"{kind.__name__}s", parameter="runs")
        if self.predictions and (self.protocol != PREFIT_PROTOCOL or self.runs):
            raise InvalidParameterError("EvaluationResult.predictions are the answer of protocol 'prefit' on logs "
                                        "without currents: no runs scored beside them", parameter="predictions")

    @property
    def scored(self) -> bool:
        """Whether the runs were scored (false only for a model fitted beforehand on logs without currents)."""
        return not self.predictions

    def total_summary(self) -> list[dict[str, Any]]:
        """Per protocol, ground (then all), model, schedule and variant: pack energy and total charge errors
        (median, p90 %) and the coverage of the 50 / 80 / 95 % intervals
        (:func:`~energy.evaluation.run_totals.summarise_totals`)."""
        return summarise_totals(self.totals)

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None) -> Path | Any:
        """Observed against nominal coverage of the total-charge intervals per protocol, ground and variant
        (:func:`~energy.evaluation.run_totals.plot_totals_reliability`).

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax`` (a matplotlib
        Axes to draw into; nothing is written and it is returned).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or ``ax``.
        """
        target = check_plot_target(path, ax)
        title = "held-out total charge (both sides)"
        if target is None:
            return plot_totals_reliability(self.totals, check_ax(ax), title=title)
        return save_figure(plot_totals_reliability(self.totals, None, title=title).figure, target)

    def row_for(self, ground: str, model: str, *, variant: str | None = None,
                schedule: str | None = None) -> ScoreRow | AdaptRow:
        """The row of one ground (or ``"all"``) and model, and (leaving one run out) variant or (adapt
        protocols) schedule; either may be left out when only one row matches.

        Raises
        ------
        UnknownNameError
            No such row, or several (give the variant or schedule).
        """
        key = {"ground": ground, "model": model, "variant": variant, "schedule": schedule}
        match = [r for r in self.rows if all(getattr(r, k, None) == v for k, v in key.items() if v is not None)]
        if len(match) == 1:
            return match[0]
        loo = self.protocol in ("loo", PREFIT_PROTOCOL)
        fields = ("variant", "ground", "model") if loo else ("ground", "model", "schedule")
        asked = ", ".join(f"{k}={v!r}" for k, v in key.items() if v is not None)
        what = "no row" if not match else f"{len(match)} rows (give the {fields[0] if loo else 'schedule'})"
        raise UnknownNameError(f"{what} for {asked}; rows exist for "
                               f"{sorted({tuple(getattr(r, k) for k in fields) for r in self.rows})!r}")

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form (NaN becomes ``None``), as written to ``evaluation.json`` (format ``terrawatt-evaluation``),
        with the adapt protocols ``adapt.json`` (``terrawatt-adaptation``); ``"prefit"``: ``predictions.json``, the
        scores with the model's label, or unscored a ``terrawatt-predictions`` document with ``"scored": false``."""
        if not self.scored:
            return result_document("predictions", PREDICTIONS_FORMAT_VERSION, {
                "model": self.label, "scored": False, "runs": [r.to_dict() for r in self.predictions]})
        common = {"total_summary": self.total_summary(), "summary": [asdict(s) for s in self.rows],
                  "totals": [t.to_dict() for t in self.totals], "runs": [asdict(r) for r in self.runs]}
        if self.protocol in _ADAPT:
            return json_finite(result_document("adaptation", ADAPT_FORMAT_VERSION, {
                "settings": dict(self.settings), "skipped": list(self.skipped), **common}))
        doc = json_finite(result_document("evaluation", EVALUATION_FORMAT_VERSION, {
            "section_s": self.section_s, "models": list(self.models), "variants": list(self.variants),
            "skipped": list(self.skipped), **common}))
        return {**doc, "model": self.label} if self.protocol == PREFIT_PROTOCOL else doc

    def summary(self) -> str:
        """Markdown tables: what the battery pays (both sides through the pack, total charge and its interval's
        coverage) first, then per side: per variant (or schedule), ground and model. ``"prefit"``: the scores per
        run and side (truth, prediction, error, RMSE), or the predictions per run."""
        if self.protocol == PREFIT_PROTOCOL:
            return _prefit_table(self.runs) if self.scored else _predictions_table(self.predictions)
        lines = []
        if self.totals:
            lines += [TOTALS_HEADING, "", totals_markdown(self.total_summary()), "Per side (charge of each motor channel):",
                      ""]
        lines += _score_table(self.rows, self.section_s) if self.protocol == "loo" else adapt_table(self.rows)
        if self.skipped:
            lines.append("")
            lines.extend(f"Skipped: {s}" for s in self.skipped)
        return "\n".join(lines) + "\n"

    def written_line(self, written: Sequence[Path], *, workers: str = "1 worker (serial)", figures: bool = False) -> str:
        """Runs, models, time and ``workers`` (where the folds ran), and the files :meth:`write` wrote (``written``);
        ``"prefit"``: the files, and, unscored, why there are no errors (and no figures, when ``figures`` were asked)."""
        if self.protocol == PREFIT_PROTOCOL:
            if not self.scored:
                missing = sum(not log.has_currents for log in self.logs)
                return (f"{missing} of {len(self.logs)} logs have no measured currents: predictions only, no errors; "
                        f"wrote {written[0]}" + (" (no figures: they compare with measured currents)" if figures else ""))
            pngs = list(written[1:])
            return f"wrote {written[0]}" + (f" and {len(pngs)} figures in {pngs[0].parent}" if pngs else "")
        names = [str(p) for p in written]
        files = ", ".join(names) if self.protocol != "loo" or len(names) < 2 else (
            ", ".join(names[:-1]) + " and " + names[-1])
        return (f"{len(self.logs)} runs, {len(self.kinds)} models, {self.duration_s:.1f} s on {workers}; "
                f"wrote {files}")

    def write(self, out_dir: str | os.PathLike[str], *, figures: bool = True, on_figure_error: str = "warn") -> list[Path]:
        """Write :func:`evaluation_files` into ``out_dir`` (created if missing) and, with ``figures``, the logs'
        vibration spectra (:data:`SPECTRA_FILE`; leaving one run out, with the header's logs) and the
        reliability figure (:data:`RELIABILITY_FILE`, :meth:`plot`); return the files written.

        ``"prefit"``: ``predictions.json`` and, scored and with ``figures``, one figure per run (measured
        and estimated current) in ``out_dir/plots`` (without measured currents there is nothing to
        compare with: no figures). A figure that fails warns
        (:class:`~terrawatt_base.errors.FigureWarning`) and is left out, unless ``on_figure_error="raise"``.

        Raises
        ------
        InvalidParameterError
            See :func:`check_evaluation_dir`.
        """
        figures = check_bool("figures", figures)
        check_choice("on_figure_error", on_figure_error, FIGURE_ERRORS)
        folder = check_evaluation_dir(out_dir, self.protocol)
        if self.protocol == PREFIT_PROTOCOL:
            files = {PREDICTIONS_FILE: lambda p: write_result_json(p, self.to_dict())}
            drawings = {f"{FIGURES_FOLDER}/current_{log.meta.ground_label}_{Path(log.meta.source).stem}.png":
                        lambda p, log=log: plot_current_estimate(log, self.model.predict(log), p, label=Path(self.label).name)
                        for log in self.logs if self.scored and self.model is not None}
        else:
            names = EVALUATION_FILES if self.protocol == "loo" else ADAPT_FILES
            files = {names[0]: lambda p: write_result_json(p, self.to_dict()),
                     names[1]: lambda p: write_text_atomic(p, self.summary())}
            drawings = {SPECTRA_FILE: lambda p: plot_vibration_spectra(list(self.logs), p)
                        } if self.protocol == "loo" and self.logs else {}
            drawings[RELIABILITY_FILE] = self.plot
        return write_answer(folder, files, drawings if figures else {}, on_figure_error=on_figure_error)


def _score_table(rows: Sequence[ScoreRow], section_s: float) -> list[str]:
    """The lines of the per-side markdown table of leave-one-run-out rows."""
    header = ["variant", "ground", "model", "runs", "whole-run median %", "whole-run p90 %",
              f"{section_s:g} s sections median %", "sections p90 %", "RMSE median A"]
    return markdown_table(header, ([s.variant, s.ground, s.model, s.n_runs, fmt_fixed(s.whole_run_median_pct),
                                    fmt_fixed(s.whole_run_p90_pct), fmt_fixed(s.section_median_pct),
                                    fmt_fixed(s.section_p90_pct), fmt_fixed(s.rmse_median_a, 2)] for s in rows), left=3)


def _prefit_table(runs: Sequence[RunScore]) -> str:
    """The scores of a model fitted beforehand per run and side: truth, prediction, error, RMSE."""
    lines = [f"{'run':<28} {'side':<6} {'truth mAh':>10} {'pred mAh':>10} {'error %':>8} {'RMSE A':>7}"]
    lines += [f"{r.run:<28} {r.side:<6} {r.charge_true_mah:>10.1f} {r.charge_predicted_mah:>10.1f} "
              f"{r.whole_run_error_pct:>8.2f} {r.rmse_a:>7.2f}" for r in runs]
    return "\n".join(lines)


def _predictions_table(predictions: Sequence[RunPrediction]) -> str:
    """The predictions per run (and what was measured, where it was)."""
    lines = [f"{'run':<28} {'pred L mAh':>10} {'pred R mAh':>10} {'meas L mAh':>10} {'meas R mAh':>10} {'pred Wh':>8}"]
    for r in predictions:
        cells = (r.charge_measured_left_mah, r.charge_measured_right_mah, r.energy_predicted_wh)
        meas_l, meas_r, wh = (f"{x:.1f}" if x == x else "-" for x in cells)
        lines.append(f"{r.run:<28} {r.charge_predicted_left_mah:>10.1f} {r.charge_predicted_right_mah:>10.1f} "
                     f"{meas_l:>10} {meas_r:>10} {wh:>8}")
    return "\n".join(lines)


def summarise_scores(scores: list[RunScore], variants: tuple[str, ...], grounds: list[str],
                     models: tuple[str, ...]) -> tuple[ScoreRow, ...]:
    """One :class:`ScoreRow` per variant, ground (then ``"all"``) and model that has scores."""
    summary: list[ScoreRow] = []
    for variant in variants:
        for g in [*grounds, _ALL]:
            for mname in models:
                rows = [s for s in scores if s.variant == variant and s.model == mname and (g == _ALL or s.ground == g)]
                if rows:
                    summary.append(_summarise(variant, g, mname, rows))
    return tuple(summary)


def evaluation_files(protocol: str = "loo") -> tuple[str, ...]:
    """The files :meth:`EvaluationResult.write` writes for ``protocol`` (the figures last; ``"prefit"``: its
    figures go into :data:`FIGURES_FOLDER`).

    Examples
    --------
    >>> evaluation_files("loo"), evaluation_files("adapt")
    (('evaluation.json', 'evaluation.md', 'spectra.png', 'reliability.png'), ('adapt.json', 'adapt.md', 'reliability.png'))
    """
    check_choice("protocol", protocol, RESULT_PROTOCOLS)
    if protocol == PREFIT_PROTOCOL:
        return (PREDICTIONS_FILE,)
    return (*EVALUATION_FILES, SPECTRA_FILE, RELIABILITY_FILE) if protocol == "loo" else (*ADAPT_FILES, RELIABILITY_FILE)


def check_evaluation_dir(out_dir: str | os.PathLike[str], protocol: str = "loo", name: str = "out_dir") -> Path:
    """Check, before any work, that :meth:`EvaluationResult.write` can write into ``out_dir``.

    Raises
    ------
    InvalidParameterError
        ``out_dir`` is a file, lies under a file, or one of :func:`evaluation_files` in it is
        a directory.
    UnknownNameError
        An unknown protocol.
    """
    folder = check_output_path(out_dir, name, directory=True)
    for file in evaluation_files(protocol):
        check_output_path(folder / file, name)
    return folder
