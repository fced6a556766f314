"""A diagnosis reported: its printed summary and its files (diagnosis.json, .md, the corrected model, figures)."""

from __future__ import annotations

import dataclasses
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from terrawatt_base.atomic import save_figure
from terrawatt_base.checks import check_choice
from terrawatt_base.errors import FigureWarning, InvalidParameterError
from terrain.terrain_map import TerrainMap

from ..logs import InteractionLog
from .diagnose import diagnose
from .model_source import ModelUnderDiagnosis
from .plots import FIGURES, plot_diagnosis, skipped_figures
from .regimes import check_terrain
from .result import Diagnosis

__all__ = ["DIAGNOSIS_FILES", "DiagnosisReport", "diagnose_report"]

#: Files :meth:`DiagnosisReport.write` writes (the figures whose data is there).
DIAGNOSIS_FILES = ("diagnosis.json", "diagnosis.md", "corrected_model.zip", *FIGURES.values())


@dataclass(frozen=True)
class DiagnosisReport:
    """A diagnosis with the logs and map it ran on, ready to print and write.

    Made by :func:`diagnose_report`. :meth:`summary` is the text ``terrawatt diagnose``
    prints, :meth:`write` writes :data:`DIAGNOSIS_FILES`.

    Attributes
    ----------
    diagnosis : Diagnosis
    logs : tuple of InteractionLog
        The logs it ran on.
    terrain : TerrainMap or None
        The map they drove on.
    """

    diagnosis: Diagnosis
    logs: tuple[InteractionLog, ...]
    terrain: TerrainMap | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.diagnosis, Diagnosis):
            raise InvalidParameterError(f"diagnosis must be a Diagnosis, got {type(self.diagnosis).__name__!r}")
        logs = tuple(self.logs)
        if not logs or not all(isinstance(log, InteractionLog) for log in logs):
            raise InvalidParameterError("logs must be a non-empty sequence of InteractionLog")
        object.__setattr__(self, "logs", logs)
        object.__setattr__(self, "terrain", check_terrain(self.terrain))

    def waterfall_table(self) -> str:
        """The held-out waterfall of the current: charge error, 8 s section error, RMSE and shrink per step."""
        lines = [f"{'step':<28} {'charge err %':>12} {'8 s sect. %':>12} {'RMSE A':>8} {'shrink %':>9}"]
        for w in self.diagnosis.waterfall:
            lines.append(f"{w.label:<28} {w.charge_error_pct:>12.2f} {w.section_error_pct:>12.2f} {w.rmse_a:>8.3f} "
                         f"{w.shrink_pct:>9.1f}")
        return "\n".join(lines)

    def power_table(self) -> str:
        """The waterfall of the battery power (``""`` without the power stage)."""
        if self.diagnosis.power is None:
            return ""
        lines = ["battery power (voltage x pack current):",
                 f"{'step':<28} {'energy err %':>12} {'8 s sect. %':>12} {'RMSE W':>8} {'shrink %':>9}"]
        for w in self.diagnosis.power.waterfall:
            lines.append(f"{w.label:<28} {w.energy_error_pct:>12.2f} {w.section_error_pct:>12.2f} {w.rmse_w:>8.2f} "
                         f"{w.shrink_pct:>9.1f}")
        return "\n".join(lines)

    def summary(self) -> str:
        """The verdict, the waterfall (and the power waterfall), and the figures skipped for want of data."""
        parts = ["\n".join(self.diagnosis.verdict), "", self.waterfall_table()]
        if self.diagnosis.power is not None:
            parts += ["", self.power_table()]
        skipped = skipped_figures(self.diagnosis, logs=list(self.logs), terrain=self.terrain)
        parts += [f"skipped {FIGURES[name]}: {why}" for name, why in skipped.items()]
        return "\n".join(parts)

    def write(self, out_dir: str | os.PathLike[str], *, on_figure_error: str = "warn") -> list[Path]:
        """Write diagnosis.json, diagnosis.md, corrected_model.zip and the figures into ``out_dir`` (created).

        The figures come last; one that fails warns (:class:`~terrawatt_base.errors.FigureWarning`,
        ``"could not draw PATH: Error: message"``) and is left out, unless
        ``on_figure_error="raise"``. Returns the files written.

        Raises
        ------
        InvalidParameterError
            A path of the wrong kind (:func:`energy.diagnosis.plot_diagnosis`).
        UnknownNameError
            An ``on_figure_error`` other than ``"warn"`` or ``"raise"``.
        """
        check_choice("on_figure_error", on_figure_error, ("warn", "raise"))
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        d = self.diagnosis
        written = [d.write_json(out / "diagnosis.json"), d.write_markdown(out / "diagnosis.md"),
                   d.corrected_model.save(out / "corrected_model.zip")]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FigureWarning)  # warned below, once, naming the file
            figures = plot_diagnosis(d, out, logs=list(self.logs), terrain=self.terrain, on_error=on_figure_error)
        for name, why in figures.failed.items():
            warnings.warn(f"could not draw {out / FIGURES[name]}: {why}", FigureWarning, stacklevel=2)
        written += list(figures.written.values())
        for drive in d.separating_drives:  # what to drive to tell tied explanations apart, and its figure
            written.append(drive.write_csv(out))
            path = out / f"{drive.file_stem}.png"
            try:
                save_figure(drive.plot(), path)
            except Exception as exc:  # noqa: BLE001 - a figure never fails the report
                if on_figure_error == "raise":
                    raise
                warnings.warn(f"could not draw {path}: {type(exc).__name__}: {exc}", FigureWarning, stacklevel=2)
            else:
                written.append(path)
        return written


def diagnose_report(source: ModelUnderDiagnosis, logs: Sequence[InteractionLog], *, terrain: TerrainMap | None = None,
                    effects: Sequence[Any] | None = None, split: str = "runs", seed: int | None = 0, client: Any = None,
                    progress: bool = False) -> DiagnosisReport:
    """Diagnose the model of ``source`` on ``logs`` (:func:`energy.diagnose`) and report it.

    The diagnosis says where its model comes from (``model_note``: ``source.note``); a model
    that is not the physics is compared with the physics of ``source.robot``.

    Parameters
    ----------
    source : ModelUnderDiagnosis
        The model (:func:`energy.diagnosis.model_under_diagnosis`).
    logs : sequence of InteractionLog
        Runs with measured currents, none of them one the model was fitted on.
    terrain, effects, split, seed, client, progress
        As :func:`energy.diagnose`.

    Returns
    -------
    DiagnosisReport

    Raises
    ------
    InvalidParameterError
        ``source`` is not a ModelUnderDiagnosis; as :func:`energy.diagnose`.
    TerrawattError
        As :func:`energy.diagnose`.
    """
    if not isinstance(source, ModelUnderDiagnosis):
        raise InvalidParameterError(f"source must be a ModelUnderDiagnosis, got {type(source).__name__!r}")
    logs = list(logs) if not isinstance(logs, InteractionLog) else [logs]
    diagnosis = diagnose(source.model, logs, terrain=terrain, effects=effects, split=split, seed=seed,
                         robot=source.reference_robot, client=client, progress=progress)
    return DiagnosisReport(dataclasses.replace(diagnosis, model_note=source.note), tuple(logs), terrain)
