"""The answer of a diagnosis, :class:`Diagnosis`: printed (``summary``), saved (``to_dict``, ``write``) and drawn
(``plot``: the effect ranking; ``write``: every figure).

``write`` writes :data:`DIAGNOSIS_FILES`: ``diagnosis.json`` (format ``terrawatt-diagnosis``),
the one-page ``diagnosis.md``, the corrected model and the figures (:mod:`energy.diagnosis.plots`).
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from terrain.terrain_map import TerrainMap
from terrawatt_base.answer import markdown_table, write_answer
from terrawatt_base.atomic import save_figure, write_text_atomic
from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import FigureWarning
from terrawatt_base.figure_file import draw_figure
from terrawatt_base.formats import result_document, write_result_json

from ..logs import InteractionLog
from ..models.base import CurrentModel
from .case import FitSettings
from .gap import GapShare, largest_slices
from .plots import FIGURES, plot_diagnosis, plot_effect_ranking, skipped_figures
from .result import Tie
from .stage import Stage

__all__ = ["DIAGNOSIS_FILES", "DIAGNOSIS_FORMAT_VERSION", "MARKDOWN_SLICES", "Diagnosis"]

#: Slices of the localisation listed in :meth:`Diagnosis.to_markdown` (the largest ``|net gap|``).
MARKDOWN_SLICES = 10
#: Version of the ``diagnosis.json`` layout (format ``terrawatt-diagnosis``, :meth:`Diagnosis.to_dict`).
DIAGNOSIS_FORMAT_VERSION = 1
#: Files :meth:`Diagnosis.write` writes (the figures whose data is there).
DIAGNOSIS_FILES = ("diagnosis.json", "diagnosis.md", "corrected_model.zip", *FIGURES.values())


def _signed(x: float, digits: int = 3) -> str:
    return ("+" if x > 0 else "") + fmt_number(x, digits)


def _interval(bounds: tuple[float, float]) -> str:
    return f"{fmt_number(bounds[0], 3)} … {fmt_number(bounds[1], 3)}"


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """What :func:`energy.diagnosis.diagnose` found (frozen), with the logs and map it ran on.

    Attributes
    ----------
    current : Stage
        The current stage (:data:`~energy.diagnosis.gap.CURRENT`): the held-out gap of the
        drive currents before and after, the ranking of the candidate effects, the chosen ones,
        the waterfall.
    localisation : tuple of GapShare
        Where the current gap of the model as given lies, on all logs: every slice of every
        dimension, each ranked by its net signed gap with a 95 % bootstrap interval
        (:func:`~energy.diagnosis.localise_gap`); :meth:`largest_slices` picks the largest.
    verdict : tuple of str
        Plain sentences: the current stage's, the power stage's (or what current logs cannot
        show), what the data could not score.
    corrected_model : CurrentModel
        The input model plus the chosen effects, fitted on all logs.
    settings : FitSettings
        The split, sections and bootstrap the stages were fitted and scored with.
    power : Stage or None
        The power stage (:data:`~energy.diagnosis.gap.POWER`: electrical effects on battery
        power) when every log carries battery voltage and pack current; None otherwise.
    model_note : str
        Where the model under test comes from (a preset as given, runs it was calibrated on,
        a file): the report's first line (:attr:`ModelUnderDiagnosis.note` when diagnosed from one).
    ties : tuple of Tie
        Per chosen effect whose step the runs cannot settle, the set of indistinguishable
        explanations (``diagnosis.json``: ``"indistinguishable"``).
    separating_drives : tuple of SeparatingDrive
        Per pair of tied explanations, the test drive that tells them apart
        (:mod:`energy.diagnosis.separating`; ``diagnosis.json``: ``"separating_drives"``).
    more_data : dict
        Where no candidate is significant: the likeliest one (``effect``, ``explanation``), its
        mean gain and spread per unit (points), the ``units_needed`` (runs or blocks like these;
        None when more would not do), the test drive that would show it (``drive``) and the
        verdict's ``sentence``; empty otherwise.
    logs : tuple of InteractionLog
        The logs it ran on (the residual figure draws them).
    terrain : TerrainMap or None
        The map they drove on.
    """

    current: Stage
    localisation: tuple[GapShare, ...]
    verdict: tuple[str, ...]
    corrected_model: CurrentModel
    settings: FitSettings = field(default_factory=FitSettings)
    power: Stage | None = None
    model_note: str = ""
    ties: tuple[Tie, ...] = ()
    separating_drives: tuple[Any, ...] = ()
    more_data: dict[str, Any] = field(default_factory=dict)
    logs: tuple[InteractionLog, ...] = ()
    terrain: TerrainMap | None = None

    def largest_slices(self, n: int = MARKDOWN_SLICES) -> tuple[GapShare, ...]:
        """The ``n`` slices of :attr:`localisation` with the largest ``|net gap|`` over all dimensions
        (:func:`~energy.diagnosis.gap.largest_slices`: unknown and one-slice dimensions left out)."""
        return largest_slices(self.localisation, n)

    @property
    def localisation_units(self) -> str:
        """What the slices' intervals resample: ``"runs"``, or ``"time sections"`` of a single run."""
        return "runs" if self.current.before.n_runs > 1 else "time sections"

    # ------------------------------------------------------------------ print
    def summary(self) -> str:
        """The verdict, the waterfall of each stage, and the figures skipped for want of data (what
        ``terrawatt diagnose`` prints)."""
        parts = ["\n".join(self.verdict), "", self.current.table()]
        if self.power is not None:
            parts += ["", self.power.table()]
        skipped = skipped_figures(self)
        parts += [f"skipped {FIGURES[name]}: {why}" for name, why in skipped.items()]
        return "\n".join(parts)

    # ------------------------------------------------------------------ save
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready result document, format ``terrawatt-diagnosis`` (the corrected model is named by class, not
        embedded; NaN left for the writer)."""
        c = self.current
        return result_document("diagnosis", DIAGNOSIS_FORMAT_VERSION, {
            "before": c.before.to_dict(),
            "after": c.after.to_dict(),
            "localisation": [r.to_dict() for r in self.localisation],
            "localisation_units": self.localisation_units,
            "ranking": [s.to_dict() for s in c.ranking],
            "chosen": list(c.chosen),
            "waterfall": [w.to_dict() for w in c.waterfall],
            "verdict": list(self.verdict),
            "model_note": self.model_note,
            "skipped": dict(c.skipped),
            "split": self.settings.split,
            "corrected_model": type(self.corrected_model).__name__,
            "indistinguishable": [t.to_dict() for t in self.ties],
            "separating_drives": [d.to_dict() for d in self.separating_drives],
            "more_data": dict(self.more_data),
        } | ({} if self.power is None else {"power": self.power.to_dict()}))

    def to_markdown(self) -> str:
        """A one-page report: the verdict, the largest slices of the gap, each stage's ranking and waterfall.

        The full slice table is in :meth:`to_dict` (``"localisation"``), not here.
        """
        c, split = self.current, self.settings.split
        lines = ["# Sim-to-real gap diagnosis", ""]
        if self.model_note:
            lines += [f"Model under test: {self.model_note}", ""]
        lines += [f"- {s}" for s in self.verdict]
        top = self.largest_slices()
        lines += ["", "## Where the gap lies (model as given, all logs)", "",
                  f"Net gap = measured - predicted charge (mAh; positive: the model predicts too little), with its "
                  f"95 % bootstrap interval over {self.localisation_units}. The {len(top)} largest of "
                  f"{len(self.localisation)} slices by |net gap|; every slice is in diagnosis.json (localisation).", ""]
        if top:
            lines += markdown_table(
                ["dimension", "slice", "net gap (mAh)", "95 % interval", "of its charge", "time (s)", "runs"],
                ([r.dimension, r.label, _signed(r.gap_mah), _interval(r.gap_interval_mah), f"{_signed(r.gap_pct)} %",
                  fmt_number(r.duration_s, 4), r.n_runs] for r in top))
        else:
            lines.append("No slice tells where: every dimension has one known slice only.")
        lines += ["", f"## Candidate effects (held-out shrink, split by {split})", "",
                  "Ranked by what each adds to the chosen effects above it; *alone* is the effect on its own. "
                  "Each fitted value beside its prior (the value that changes nothing) and its plausible range; "
                  "flags: a value outside it or pinned at a fitting bound (doubtful), also of the effect fitted "
                  "alone.", ""]
        lines += markdown_table(["rank", "effect", "kind", "adds", "95 % interval", "alone", "parameters", "flags"], (
            [k, s.name + (" (chosen)" if s.name in c.chosen else ""), s.kind, f"{fmt_number(s.added_pct, 3)} %",
             f"{_interval(s.added_interval_pct)} %", f"{fmt_number(s.shrink_pct, 3)} %", s.parameter_text(),
             "; ".join([*s.flags, *(["fitted alone: " + "; ".join(s.alone_flags)]
                                    if s.alone_flags and s.alone_parameters != s.parameters else [])]) or "–"]
            for k, s in enumerate(c.ranking, 1)))
        if c.skipped:
            lines += ["", "Not scored: " + "; ".join(f"{n} ({why})" for n, why in c.skipped.items()) + "."]
        lines += ["", "## Waterfall (held-out)", "", *c.waterfall_markdown()]
        if self.power is not None:
            lines += ["", f"## Battery power: electrical candidates (held-out shrink, split by {split})", "",
                      "Measured battery power = voltage x pack current; predicted from the measured drive currents "
                      "with the model's electrical basis.", ""]
            lines += markdown_table(["rank", "effect", "adds", "95 % interval", "alone", "parameters"], (
                [k, s.name, f"{fmt_number(s.added_pct, 3)} %", f"{_interval(s.added_interval_pct)} %",
                 f"{fmt_number(s.shrink_pct, 3)} %", ", ".join(f"{n} = {fmt_number(v, 4)}" for n, v in s.parameters.items())]
                for k, s in enumerate(self.power.ranking, 1)))
            lines += ["", *self.power.waterfall_markdown()]
        return "\n".join(lines) + "\n"

    # ------------------------------------------------------------------ draw
    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None, max_effects: int = 20,
             dpi: int = 110) -> Path | Any:
        """The main figure, the effect ranking: what each candidate adds to the chosen effects above it
        (:func:`~energy.diagnosis.plots.plot_effect_ranking`; :meth:`write` draws every figure).

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax`` (a matplotlib
        Axes to draw into; nothing is written and it is returned).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path``, ``ax`` or ``max_effects``.
        DataError
            No candidate was scored.
        """
        return plot_effect_ranking(self, path, ax=ax, max_effects=max_effects, dpi=dpi)

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
        out = Path(out_dir)
        written = write_answer(out, {"diagnosis.json": lambda p: write_result_json(p, self.to_dict()),
                                     "diagnosis.md": lambda p: write_text_atomic(p, self.to_markdown()),
                                     "corrected_model.zip": self.corrected_model.save}, on_figure_error=on_figure_error)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FigureWarning)  # warned below, once, naming the file
            figures = plot_diagnosis(self, out, on_error=on_figure_error)
        for name, why in figures.failed.items():
            warnings.warn(f"could not draw {out / FIGURES[name]}: {why}", FigureWarning, stacklevel=2)
        written += list(figures.written.values())
        for drive in self.separating_drives:  # what to drive to tell tied explanations apart, and its figure
            written.append(drive.write_csv(out))
            path = out / f"{drive.file_stem}.png"
            if draw_figure(path, lambda d=drive, p=path: save_figure(d.plot(), p), on_error=on_figure_error):
                written.append(path)
        return written
