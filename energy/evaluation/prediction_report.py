"""A fitted model applied to logs and reported: its scores, or its predictions where currents are missing."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from terrawatt_base.formats import result_document, write_result_json
from terrawatt_base.checks import check_bool, check_choice, check_text
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.figure_file import draw_figure

from ..logs import InteractionLog
from ..models.base import CurrentModel
from ..plots import plot_current_estimate
from ..prediction import RunPrediction, predict_runs
from .results import EvaluationResult
from .scoring import score_current_model

__all__ = ["PREDICTIONS_FILE", "PREDICTIONS_FORMAT_VERSION", "FIGURES_FOLDER", "PredictionReport", "predict_report"]

#: The file :meth:`PredictionReport.write` writes, and the folder of its figures.
PREDICTIONS_FILE = "predictions.json"
#: Format version of an unscored ``predictions.json`` (``terrawatt-predictions``; a scored one is an evaluation).
PREDICTIONS_FORMAT_VERSION = 1
FIGURES_FOLDER = "plots"


@dataclass(frozen=True)
class PredictionReport:
    """A fitted model on logs: per-run scores when every log has measured currents, else predictions only.

    Made by :func:`predict_report`. :meth:`summary` is the table ``terrawatt predict`` prints,
    :meth:`to_dict` the content of ``predictions.json``, :meth:`write` writes it (and the figures).

    Attributes
    ----------
    model : CurrentModel
        The fitted model.
    logs : tuple of InteractionLog
    label : str
        How the files name the model (e.g. its file); its last path part names it in the scores.
    scores : EvaluationResult or None
        Charge errors per run and side (:func:`energy.evaluation.score_current_model`); None when
        some log has no measured currents.
    runs : tuple of RunPrediction
        Predictions per run (:func:`energy.prediction.predict_runs`); empty when scored.
    """

    model: CurrentModel
    logs: tuple[InteractionLog, ...]
    label: str
    scores: EvaluationResult | None
    runs: tuple[RunPrediction, ...] = ()

    @property
    def scored(self) -> bool:
        """Whether every log had measured currents (and the model was scored)."""
        return self.scores is not None

    @property
    def name(self) -> str:
        """The model's name: the last part of :attr:`label`."""
        return Path(self.label).name

    def summary(self) -> str:
        """The scores per run and side (truth, prediction, error, RMSE), or the predictions per run."""
        if self.scores is not None:
            lines = [f"{'run':<28} {'side':<6} {'truth mAh':>10} {'pred mAh':>10} {'error %':>8} {'RMSE A':>7}"]
            lines += [f"{r.run:<28} {r.side:<6} {r.charge_true_mah:>10.1f} {r.charge_predicted_mah:>10.1f} "
                      f"{r.whole_run_error_pct:>8.2f} {r.rmse_a:>7.2f}" for r in self.scores.runs]
            return "\n".join(lines)
        lines = [f"{'run':<28} {'pred L mAh':>10} {'pred R mAh':>10} {'meas L mAh':>10} {'meas R mAh':>10} {'pred Wh':>8}"]
        for r in self.runs:
            cells = (r.charge_measured_left_mah, r.charge_measured_right_mah, r.energy_predicted_wh)
            meas_l, meas_r, wh = (f"{x:.1f}" if x == x else "-" for x in cells)
            lines.append(f"{r.run:<28} {r.charge_predicted_left_mah:>10.1f} {r.charge_predicted_right_mah:>10.1f} "
                         f"{meas_l:>10} {meas_r:>10} {wh:>8}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """``predictions.json``: the scores (a ``terrawatt-evaluation`` result document) with the model's label, or
        a ``terrawatt-predictions`` document with ``"scored": false`` and the predictions."""
        if self.scores is not None:
            return {**self.scores.to_dict(), "model": self.label}
        return result_document("predictions", PREDICTIONS_FORMAT_VERSION,
                               {"model": self.label, "scored": False, "runs": [r.to_dict() for r in self.runs]})

    def written_line(self, written: Sequence[Path], *, figures: bool = False) -> str:
        """The line saying what :meth:`write` wrote (``written``, its return) and, unscored, why there are no errors."""
        if self.scores is None:
            missing = sum(not log.has_currents for log in self.logs)
            return (f"{missing} of {len(self.logs)} logs have no measured currents: predictions only, no errors; "
                    f"wrote {written[0]}" + (" (no figures: they compare with measured currents)" if figures else ""))
        pngs = list(written[1:])
        return f"wrote {written[0]}" + (f" and {len(pngs)} figures in {pngs[0].parent}" if pngs else "")

    def write(self, out_dir: str | os.PathLike[str], *, figures: bool = False,
              on_figure_error: str = "warn") -> list[Path]:
        """Write ``predictions.json`` into ``out_dir`` (created) and, scored and with ``figures``, one figure per
        run (measured and estimated current) into ``out_dir/plots``; return the files written.

        A figure that fails warns (:class:`~terrawatt_base.errors.FigureWarning`) and is left out,
        unless ``on_figure_error="raise"``. Without measured currents there is nothing to compare
        with: no figures.
        """
        figures = check_bool("figures", figures)
        check_choice("on_figure_error", on_figure_error, ("warn", "raise"))
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written = [write_result_json(out / PREDICTIONS_FILE, self.to_dict())]
        if not (figures and self.scored):
            return written
        for log in self.logs:
            png = out / FIGURES_FOLDER / f"current_{log.meta.ground_label}_{Path(log.meta.source).stem}.png"
            done = draw_figure(png, lambda log=log, png=png: plot_current_estimate(
                log, self.model.predict(log), png, label=self.name), on_error=on_figure_error)
            if done is not None:
                written.append(done)
        return written


def predict_report(model: CurrentModel, logs: Sequence[InteractionLog], *, label: str = "model") -> PredictionReport:
    """Apply a fitted model to logs: score it (:func:`score_current_model`) when every log has measured currents,
    else predict each run (:func:`energy.prediction.predict_runs`).

    Parameters
    ----------
    model : CurrentModel
        A fitted model (e.g. :func:`energy.load_current_model`).
    logs : sequence of InteractionLog
    label : str
        How the files name the model (e.g. its file); its last path part names it in the scores.

    Returns
    -------
    PredictionReport

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel, no logs, a blank label.
    NotFittedError, DataError
        As ``model.predict``.
    """
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a CurrentModel, got {type(model).__name__!r}")
    label = check_text("label", label)
    items = [logs] if isinstance(logs, InteractionLog) else list(logs)
    if not items or not all(isinstance(log, InteractionLog) for log in items):
        raise InvalidParameterError("logs must be one InteractionLog or a non-empty sequence of them")
    if all(log.has_currents for log in items):
        return PredictionReport(model, tuple(items), label, score_current_model(model, items, name=Path(label).name))
    return PredictionReport(model, tuple(items), label, None, tuple(predict_runs(model, items)))
