"""The result of a diagnosis: effect scores, the held-out waterfall, the verdict, the corrected model."""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from terrawatt_base.atomic import write_text_atomic
from terrawatt_base.checks import fmt_number
from terrawatt_base.formats import result_document, write_result_json

from ..models.base import CurrentModel
from .gap import GapShare, GapSummary, largest_slices

__all__ = ["EffectScore", "Tie", "WaterfallStep", "Diagnosis", "MARKDOWN_SLICES", "DIAGNOSIS_FORMAT_VERSION"]

#: Slices of the localisation listed in :meth:`Diagnosis.to_markdown` (the largest ``|net gap|``).
MARKDOWN_SLICES = 10
#: Version of the ``diagnosis.json`` layout (format ``terrawatt-diagnosis``) written by :meth:`Diagnosis.write_json`.
DIAGNOSIS_FORMAT_VERSION = 1


@dataclass(frozen=True)
class EffectScore:
    """One candidate effect, fitted on calibration data and scored on held-out data.

    Attributes
    ----------
    name, kind : str
        Catalogue name; ``"physics"``, ``"parameter"``, ``"measurement"`` or ``"learned"``.
    parameters : dict of str to float
        Fitted values (median over the folds' calibration fits).
    shrink_pct : float
        ``100 * (1 - MSE_after / MSE_before)`` of the current over the held-out samples.
        The effect alone on the model as given.
    shrink_interval_pct : (float, float)
        95 % bootstrap interval of the shrink over runs (or blocks).
    n_parameters : int
    added_pct : float
        Points of the original squared gap it adds, fitted jointly with the effects ranked
        above it that were chosen (equal to ``shrink_pct`` for the first).
    added_interval_pct : (float, float)
        95 % bootstrap interval of ``added_pct``.
    priors : dict of str to float
        Per parameter, the value that changes nothing: the model's own value of a parameter
        the effect re-predicts (mass scale 1, its rolling resistance, motor-constant scale 1),
        1 for a gain, 0 for an offset or a lag (:meth:`Effect.priors`).
    plausible : dict of str to (float, float)
        Per parameter, its physical plausible range (separate from the wider fitting bounds).
    flags : tuple of str
        What makes the fitted values doubtful and why: a value outside its plausible range,
        a value pinned at a fitting bound. Empty when every value is plausible.
    doubtful : bool
        ``bool(flags)`` (a property; in :meth:`to_dict` too).
    summary : str
        The fitted values in plain words (e.g. ``"mass +80 kg (x1.8 of the robot's 100 kg)"``).
    alone_parameters, alone_flags, alone_summary
        The same for the effect fitted on its own (what ``shrink_pct`` scores): a candidate
        can look plausible beside the chosen effects and implausible alone, or the reverse.
    """

    name: str
    kind: str
    parameters: dict[str, float]
    shrink_pct: float
    shrink_interval_pct: tuple[float, float]
    n_parameters: int
    added_pct: float = float("nan")
    added_interval_pct: tuple[float, float] = (float("nan"), float("nan"))
    priors: dict[str, float] = field(default_factory=dict)
    plausible: dict[str, tuple[float, float]] = field(default_factory=dict)
    flags: tuple[str, ...] = ()
    summary: str = ""
    alone_parameters: dict[str, float] = field(default_factory=dict)
    alone_flags: tuple[str, ...] = ()
    alone_summary: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        d = asdict(self)
        d["shrink_interval_pct"] = list(self.shrink_interval_pct)
        d["added_interval_pct"] = list(self.added_interval_pct)
        d["plausible"] = {k: list(v) for k, v in self.plausible.items()}
        d["flags"] = list(self.flags)
        d["doubtful"] = self.doubtful
        d["alone_flags"] = list(self.alone_flags)
        return d

    @property
    def doubtful(self) -> bool:
        """Whether the fitted values are flagged (outside their plausible range or at a fitting bound)."""
        return bool(self.flags)

    def parameter_text(self) -> str:
        """Each fitted value beside its prior and plausible range: ``"mass_scale = 1.8 (prior 1; plausible 0.5 … 2.5)"``."""
        parts = []
        for n, v in self.parameters.items():
            extra = []
            if n in self.priors:
                extra.append(f"prior {fmt_number(self.priors[n], 4)}")
            if n in self.plausible:
                lo, hi = self.plausible[n]
                extra.append(f"plausible {fmt_number(lo, 3)} … {fmt_number(hi, 3)}")
            parts.append(f"{n} = {fmt_number(v, 4)}" + (f" ({'; '.join(extra)})" if extra else ""))
        return ", ".join(parts)


@dataclass(frozen=True)
class Tie:
    """Explanations the runs cannot tell apart: the chosen effect and the candidates as good as it.

    Attributes
    ----------
    chosen : str
        The effect the selection added (the corrected model is built from it, one of the set).
    alternatives : tuple of str
        Candidates with plausible values that would have been as significant, whose paired
        held-out difference from ``chosen`` the bootstrap cannot order at 95 %.
    explanations : dict of str to str
        Each effect of the set in physical terms, fitted at that step ("mass +29 kg (x1.58 ...)").
    added_pct : dict of str to float
        What each would add at that step (points of the original squared gap).
    run_difference_pct : dict of str to (float, float, float)
        Per alternative, how far ``chosen`` is ahead of it per run (or block), in points of that
        unit's own gap: the mean over the units and its 95 % bootstrap interval
        (:func:`~energy.diagnosis.selection.unit_gain_interval`; a tie: no unit puts it 2 points
        ahead, or the interval holds 0).
    """

    chosen: str
    alternatives: tuple[str, ...]
    explanations: dict[str, str]
    added_pct: dict[str, float]
    run_difference_pct: dict[str, tuple[float, float, float]]

    @property
    def effects(self) -> tuple[str, ...]:
        """The set: the chosen effect first."""
        return (self.chosen, *self.alternatives)

    def sentence(self) -> str:
        """The verdict's sentence on the tie."""
        parts = [self.explanations[n] for n in self.effects]
        listed = ", ".join(parts[:-1]) + f" or {parts[-1]}"
        shares = " / ".join(fmt_number(self.added_pct[n], 3) for n in self.effects)
        ahead = "; ".join(f"{self.chosen} ahead of {a} by {fmt_number(m, 2)} points of a run's gap (95 % interval "
                          f"{fmt_number(lo, 2)} … {fmt_number(hi, 2)})"
                          for a, (m, lo, hi) in self.run_difference_pct.items())
        return (f"{listed}: these runs cannot tell them apart (they explain {shares} % of the squared gap; {ahead}); "
                f"the corrected model uses {self.chosen}, one of the set.")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"chosen": self.chosen, "alternatives": list(self.alternatives), "effects": list(self.effects),
                "explanations": dict(self.explanations), "added_pct": dict(self.added_pct),
                "run_difference_pct": {k: dict(zip(("mean", "low", "high"), v))
                                       for k, v in self.run_difference_pct.items()}}


@dataclass(frozen=True)
class WaterfallStep:
    """The held-out gap after one more effect: whole-set charge error, 8 s section error, RMSE, shrink."""

    label: str
    charge_error_pct: float
    section_error_pct: float
    rmse_a: float
    shrink_pct: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


def _signed(x: float, digits: int = 3) -> str:
    return ("+" if x > 0 else "") + fmt_number(x, digits)


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """What :func:`energy.diagnosis.diagnose` found (frozen).

    Attributes
    ----------
    before, after : GapSummary
        Held-out gap of the model as given and of the corrected model (each sample
        predicted by the fold that held it out).
    localisation : tuple of GapShare
        Where the gap of the model as given lies, on all logs: every slice of every
        dimension, each ranked by its net signed gap with a 95 % bootstrap interval
        (:func:`~energy.diagnosis.localise_gap`); :meth:`largest_slices` picks the largest.
    ranking : tuple of EffectScore
        Every candidate: the chosen effects in the order they were added (each the best
        addition to those before it), then the others by what they would add to the chosen
        set (best first).
    chosen : tuple of str
        Effects added greedily, in order.
    waterfall : tuple of WaterfallStep
        ``"as given"``, then one step per chosen effect.
    verdict : tuple of str
        Plain sentences.
    corrected_model : CurrentModel
        The input model plus the chosen effects, fitted on all logs.
    skipped : dict of str to str
        Candidates not scored and why (already in the model, data cannot show them).
    split : {"runs", "blocks"}
    power : PowerDiagnosis or None
        The power stage (electrical effects on battery power) when every log carries battery
        voltage and pack current; None otherwise.
    model_note : str
        Where the model under test comes from (a preset as given, runs it was calibrated on,
        a file), when the caller states it (``dataclasses.replace(d, model_note=...)``, as
        ``terrawatt diagnose`` does); the report's first line.
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
    """

    before: GapSummary
    after: GapSummary
    localisation: tuple[GapShare, ...]
    ranking: tuple[EffectScore, ...]
    chosen: tuple[str, ...]
    waterfall: tuple[WaterfallStep, ...]
    verdict: tuple[str, ...]
    corrected_model: CurrentModel
    skipped: dict[str, str] = field(default_factory=dict)
    split: str = "runs"
    power: Any = None
    model_note: str = ""
    ties: tuple[Tie, ...] = ()
    separating_drives: tuple[Any, ...] = ()
    more_data: dict[str, Any] = field(default_factory=dict)

    @property
    def found(self) -> bool:
        """Whether a catalogued (non-learned) effect explains part of the gap."""
        kinds = {s.name: s.kind for s in self.ranking}
        return any(kinds.get(n) != "learned" for n in self.chosen)

    def score(self, name: str) -> EffectScore | None:
        """The ranking entry of ``name``, or None."""
        return next((s for s in self.ranking if s.name == name), None)

    def largest_slices(self, n: int = MARKDOWN_SLICES) -> tuple[GapShare, ...]:
        """The ``n`` slices of :attr:`localisation` with the largest ``|net gap|`` over all dimensions
        (:func:`~energy.diagnosis.gap.largest_slices`: unknown and one-slice dimensions left out)."""
        return largest_slices(self.localisation, n)

    @property
    def localisation_units(self) -> str:
        """What the slices' intervals resample: ``"runs"``, or ``"time sections"`` of a single run."""
        return "runs" if self.before.n_runs > 1 else "time sections"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready result document, format ``terrawatt-diagnosis`` (the corrected model is named by class, not
        embedded; NaN left for the writer)."""
        return result_document("diagnosis", DIAGNOSIS_FORMAT_VERSION, {
            "before": self.before.to_dict(),
            "after": self.after.to_dict(),
            "localisation": [r.to_dict() for r in self.localisation],
            "localisation_units": self.localisation_units,
            "ranking": [s.to_dict() for s in self.ranking],
            "chosen": list(self.chosen),
            "waterfall": [w.to_dict() for w in self.waterfall],
            "verdict": list(self.verdict),
            "model_note": self.model_note,
            "skipped": dict(self.skipped),
            "split": self.split,
            "corrected_model": type(self.corrected_model).__name__,
            "indistinguishable": [t.to_dict() for t in self.ties],
            "separating_drives": [d.to_dict() for d in self.separating_drives],
            "more_data": dict(self.more_data),
        } | ({} if self.power is None else {"power": self.power.to_dict()}))

    def write_json(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_dict` to ``path`` atomically (:func:`~terrawatt_base.formats.write_result_json`)."""
        return write_result_json(path, self.to_dict())

    def to_markdown(self) -> str:
        """A one-page report: the verdict, the largest slices of the gap, the effect ranking and the waterfall.

        The full slice table is in :meth:`to_dict` (``"localisation"``), not here.
        """
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
            lines += ["| dimension | slice | net gap (mAh) | 95 % interval | of its charge | time (s) | runs |",
                      "|---|---|---|---|---|---|---|"]
            for r in top:
                lo, hi = r.gap_interval_mah
                lines.append(f"| {r.dimension} | {r.label} | {_signed(r.gap_mah)} | {fmt_number(lo, 3)} … "
                             f"{fmt_number(hi, 3)} | {_signed(r.gap_pct)} % | {fmt_number(r.duration_s, 4)} | "
                             f"{r.n_runs} |")
        else:
            lines.append("No slice tells where: every dimension has one known slice only.")
        lines += ["", f"## Candidate effects (held-out shrink, split by {self.split})", "",
                  "Ranked by what each adds to the chosen effects above it; *alone* is the effect on its own. "
                  "Each fitted value beside its prior (the value that changes nothing) and its plausible range; "
                  "flags: a value outside it or pinned at a fitting bound (doubtful), also of the effect fitted alone.", "",
                  "| rank | effect | kind | adds | 95 % interval | alone | parameters | flags |",
                  "|---|---|---|---|---|---|---|---|"]
        for k, s in enumerate(self.ranking, 1):
            lo, hi = s.added_interval_pct
            flags = list(s.flags)
            if s.alone_flags and s.alone_parameters != s.parameters:
                flags.append("fitted alone: " + "; ".join(s.alone_flags))
            flags = "; ".join(flags) if flags else "–"
            lines.append(f"| {k} | {s.name}{' (chosen)' if s.name in self.chosen else ''} | {s.kind} | "
                         f"{fmt_number(s.added_pct, 3)} % | {fmt_number(lo, 3)} … {fmt_number(hi, 3)} % | "
                         f"{fmt_number(s.shrink_pct, 3)} % | {s.parameter_text()} | {flags} |")
        if self.skipped:
            lines += ["", "Not scored: " + "; ".join(f"{n} ({why})" for n, why in self.skipped.items()) + "."]
        lines += ["", "## Waterfall (held-out)", "",
                  "| step | charge error | 8 s section error | RMSE (A) | shrink |", "|---|---|---|---|---|"]
        for w in self.waterfall:
            lines.append(f"| {w.label} | {fmt_number(w.charge_error_pct, 3)} % | {fmt_number(w.section_error_pct, 3)} % | "
                         f"{fmt_number(w.rmse_a, 3)} | {fmt_number(w.shrink_pct, 3)} % |")
        if self.power is not None:
            lines += self.power.markdown_lines(self.split)
        return "\n".join(lines) + "\n"

    def write_markdown(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_markdown` to ``path`` atomically; return the path."""
        return write_text_atomic(path, self.to_markdown())
