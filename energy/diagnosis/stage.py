"""One stage of a diagnosis: the effects that explain the held-out gap of one quantity (current or battery power).

A diagnosis has a stage per :class:`~energy.diagnosis.gap.Quantity` it can measure: the drive
currents always (:data:`~energy.diagnosis.gap.CURRENT`, the catalogue's drive, parameter and
measurement effects), the battery power when every log carries battery voltage and pack current
(:data:`~energy.diagnosis.gap.POWER`, the electrical effects, predicted from the measured drive
currents with the model's electrical basis: :mod:`energy.diagnosis.power_data`). Both stages fit
their candidates on calibration runs or blocks and score them on held-out ones with the same
split, bootstrap and greedy significance rule (:func:`~energy.diagnosis.selection.select_effects`),
and each answers with one :class:`Stage`: the held-out gap before and after, the ranking, the
chosen effects, the waterfall and the verdict's sentences (:func:`stage_verdict`), in the
quantity's units and words.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number, fmt_pct

from ..robot import RobotParams
from .case import DiagnosisData, FitSettings
from .effect_base import Effect
from .fit import SetRunner, fit_effect_set
from .gap import GapShare, GapSummary, WaterfallStep, gap_summary, largest_slices
from .model_currents import PhysicsBasis
from .quantity import CURRENT, POWER, Quantity
from .result import EffectScore, Tie
from .selection import Selection, plausible_alternative, select_effects, shrink_pct

__all__ = ["Stage", "stage_of", "stage_verdict", "power_stage", "CONFUSED_FRACTION"]

#: A candidate whose shrink alone reaches this fraction of the chosen one's is called hard to tell apart from it
#: (the power stage's verdict).
CONFUSED_FRACTION = 0.8
# what would separate two electrical effects that the data cannot tell apart
_SEPARATES = {frozenset(("sensor", "control")): "stops, the start-up after a stop or a per-device current separate them",
              frozenset(("sensor", "armature_heat")): "runs of very different drive currents separate them",
              frozenset(("control", "armature_heat")): "runs of very different drive currents separate them"}


@dataclass(frozen=True, eq=False)
class Stage:
    """What one stage of :func:`energy.diagnosis.diagnose` found for its quantity (frozen).

    Attributes
    ----------
    quantity : Quantity
        :data:`~energy.diagnosis.gap.CURRENT` or :data:`~energy.diagnosis.gap.POWER`: the units
        and words of everything below.
    before, after : GapSummary
        Held-out gap of the model as given and with the chosen effects (each sample predicted by
        the fold that held it out).
    ranking : tuple of EffectScore
        Every candidate: the chosen effects in the order they were added (each the best addition
        to those before it), then the others by what they would add to the chosen set.
    chosen : tuple of str
        Effects added greedily, in order.
    waterfall : tuple of WaterfallStep
        ``"as given"``, then one step per chosen effect.
    verdict : tuple of str
        The stage's plain sentences (:func:`stage_verdict`).
    skipped : dict of str to str
        Candidates not scored and why.
    fitted : dict of str to dict of str to float
        The power stage: the chosen effects' values fitted jointly on all logs.
    corrected_robot : RobotParams or None
        The power stage: the basis robot with the fitted values (armature resistance, sensor and
        control powers).
    corrected_effects : tuple of str
        The power stage: the basis effects plus the chosen ones; ``PhysicsEnergyModel(corrected_robot,
        corrected_effects)`` predicts the battery power with them.
    """

    quantity: Quantity
    before: GapSummary
    after: GapSummary
    ranking: tuple[EffectScore, ...]
    chosen: tuple[str, ...]
    waterfall: tuple[WaterfallStep, ...]
    verdict: tuple[str, ...] = ()
    skipped: dict[str, str] = field(default_factory=dict)
    fitted: dict[str, dict[str, float]] = field(default_factory=dict)
    corrected_robot: RobotParams | None = None
    corrected_effects: tuple[str, ...] = ()

    @property
    def found(self) -> bool:
        """Whether a catalogued (non-learned) effect explains part of the gap."""
        kinds = {s.name: s.kind for s in self.ranking}
        return any(kinds.get(n) != "learned" for n in self.chosen)

    def score(self, name: str) -> EffectScore | None:
        """The ranking entry of ``name``, or None."""
        return next((s for s in self.ranking if s.name == name), None)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict of a power stage (``diagnosis.json``: ``"power"``; the corrected robot by its electrical
        values). The current stage's figures stand at the top of ``diagnosis.json`` (:meth:`Diagnosis.to_dict`)."""
        rb = self.corrected_robot
        return {
            "before": self.before.to_dict(), "after": self.after.to_dict(),
            "ranking": [s.to_dict() for s in self.ranking], "chosen": list(self.chosen),
            "waterfall": [w.to_dict() for w in self.waterfall], "verdict": list(self.verdict),
            "fitted": {k: dict(v) for k, v in self.fitted.items()}, "skipped": dict(self.skipped),
            "corrected_effects": list(self.corrected_effects),
            "corrected_robot": None if rb is None else {
                "name": rb.name, "armature_resistance_ohm": rb.motor.armature_resistance_ohm,
                "sensor_power_w": rb.sensor_power_w, "sensor_power_per_mps_w": rb.sensor_power_per_mps_w,
                "control_standby_power_w": rb.control_standby_power_w,
                "control_stable_power_w": rb.control_stable_power_w},
        }

    def waterfall_markdown(self) -> list[str]:
        """The waterfall as a markdown table: the error of the total, the 8 s section error, the RMSE, the shrink."""
        q = self.quantity
        lines = [f"| step | {q.total_name} error | 8 s section error | RMSE ({q.unit}) | shrink |", "|---|---|---|---|---|"]
        for w in self.waterfall:
            lines.append(f"| {w.label} | {fmt_number(w.error_pct, 3)} % | {fmt_number(w.section_error_pct, 3)} % "
                         f"| {fmt_number(w.rmse, q.rmse_digits)} | {fmt_number(w.shrink_pct, 3)} % |")
        return lines

    def table(self) -> str:
        """The waterfall as printed text (``terrawatt diagnose``), under the quantity's title."""
        q = self.quantity
        err = f"{q.total_name} err %"
        lines = [f"{q.title}:"] if q.title else []
        lines.append(f"{'step':<28} {err:>12} {'8 s sect. %':>12} {'RMSE ' + q.unit:>8} {'shrink %':>9}")
        for w in self.waterfall:
            lines.append(f"{w.label:<28} {w.error_pct:>12.2f} {w.section_error_pct:>12.2f} "
                         f"{w.rmse:>8.{q.rmse_decimals}f} {w.shrink_pct:>9.1f}")
        return "\n".join(lines)


def stage_of(quantity: Quantity, data: DiagnosisData, sel: Selection, settings: FitSettings, **extra: Any) -> Stage:
    """The :class:`Stage` of a selection on ``data``: its ranking, chosen effects and held-out waterfall (``"as
    given"``, then ``"+ effect"`` per chosen effect, each the :func:`~energy.diagnosis.gap.gap_summary` of the held-out
    prediction after it: the first is the gap before, the last the gap after). ``extra``: the other fields of
    :class:`Stage`; the verdict is the caller's (:func:`stage_verdict`)."""
    stopped = None if data.stopped is None else list(data.stopped)
    gaps = [gap_summary(data.logs, list(s.held_out_a), quantity=quantity, stopped=stopped, section_s=settings.section_s)
            for s in sel.sets]
    labels = ["as given"] + [f"+ {e.name}" for e in sel.chosen]
    steps = tuple(WaterfallStep.of(label, g, shrink_pct(sel.none, s)) for label, g, s in zip(labels, gaps, sel.sets))
    return Stage(quantity, gaps[0], gaps[-1], tuple(sel.scores[e.name] for e in sel.order),
                 tuple(e.name for e in sel.chosen), steps, **extra)


# ---------------------------------------------------------------------- the verdict
def _largest_slice_clause(localisation: Sequence[GapShare]) -> str:
    """The clause on the largest net slice (``largest_slices``), or ``""`` when no slice tells where."""
    top = largest_slices(localisation, 1)
    if not top:
        return ""
    best = top[0]
    whole = sum(r.gap_mah for r in localisation if r.dimension == "side")
    total_s = sum(r.duration_s for r in localisation if r.dimension == "time")
    lo, hi = best.gap_interval_mah
    sign = "+" if best.gap_mah > 0 else ""
    text = (f"; the largest net slice is {best.dimension} {best.label!r}: {sign}{fmt_number(best.gap_mah, 3)} mAh "
            f"(95 % interval {fmt_number(lo, 3)} … {fmt_number(hi, 3)} mAh)")
    if math.isfinite(best.gap_pct):
        text += f", {sign}{fmt_pct(best.gap_pct)} % of that slice's charge"
    if total_s > 0:
        text += f", in {fmt_pct(100.0 * best.duration_s / total_s)} % of the time"
    if abs(best.gap_mah) > abs(whole) * (1.0 + 1e-9) + 1e-12:
        text += f" — more than the whole net gap of {fmt_number(whole, 3)} mAh: slices of opposite sign cancel in the total"
    return text


def _opening(stage: Stage, localisation: Sequence[GapShare]) -> str:
    b = stage.before
    if stage.quantity is CURRENT:
        return (f"The gap is {fmt_pct(b.error_pct)} % of the charge (RMSE {fmt_number(b.rmse, 3)} A)"
                f"{_largest_slice_clause(localisation)}.")
    return (f"Battery power (voltage x pack current, in every log): the model's electrical basis, fed the measured "
            f"drive currents, misses {fmt_pct(b.error_pct)} % of the battery energy (RMSE {fmt_number(b.rmse, 3)} W); "
            f"{fmt_pct(b.stopped_gap_pct)} % of that gap falls while the robot stands still "
            f"({fmt_pct(b.stopped_time_pct)} % of the time).")


def _effect_sentence(stage: Stage, k: int, s: EffectScore, held: str) -> str:
    lo, hi = s.added_interval_pct
    interval = f"95 % interval {fmt_number(lo, 3)} … {fmt_number(hi, 3)}"
    if stage.quantity is POWER:
        params = ", ".join(f"{p} = {fmt_number(v, 4)}" for p, v in s.parameters.items())
        lead = f"{s.name} (electrical; {params})" if k == 0 else f"Then {s.name} (electrical; {params}), fitted jointly,"
        return f"{lead} explains {fmt_number(s.added_pct, 3)} % of the squared power gap on {held} ({interval} %)."
    what = ("A learned residual correction (last resort, not physics)" if s.kind == "learned"
            else f"{s.name} ({s.kind}{'; doubtful' if s.kind != 'learned' and s.doubtful else ''})")
    if k == 0:
        return f"{what} explains {fmt_number(s.added_pct, 3)} % of the squared current gap on {held} ({interval} %)."
    return (f"Then {what}, fitted jointly with the effects before it, explains a further "
            f"{fmt_number(s.added_pct, 3)} points ({interval}; {fmt_number(s.shrink_pct, 3)} % alone).")


def _doubt_sentence(stage: Stage, s: EffectScore) -> str:
    n = s.name
    a_lo, a_hi = s.shrink_interval_pct
    text = f"{n} is doubtful: {'; '.join(s.flags)}."
    alt = plausible_alternative(s, stage.ranking, stage.chosen)
    if alt is not None:
        return text + (f" {alt.alone_summary} explains a similar held-out gap with plausible values "
                       f"({fmt_number(alt.shrink_pct, 3)} % alone, within {n}'s 95 % interval "
                       f"{fmt_number(a_lo, 3)} … {fmt_number(a_hi, 3)} %): the likelier cause.")
    return text + (f" No candidate with plausible values explains a similar held-out gap (within {n}'s 95 % "
                   f"interval {fmt_number(a_lo, 3)} … {fmt_number(a_hi, 3)} % alone): {n} may stand in for "
                   "an effect outside the catalogue.")


def _closing(stage: Stage, held: str) -> str:
    before, after, names = stage.before, stage.after, ", ".join(stage.chosen)
    if stage.quantity is POWER:
        return (f"With {names} added, the battery-energy error on {held} goes from {fmt_pct(before.error_pct)} % to "
                f"{fmt_pct(after.error_pct)} % (RMSE {fmt_number(before.rmse, 3)} -> {fmt_number(after.rmse, 3)} W).")
    shrink = 100.0 * (1.0 - (after.rmse / before.rmse) ** 2) if before.rmse > 0 else 0.0
    text = (f"With {names} added, the squared current gap on {held} shrinks by {fmt_number(shrink, 3)} % (RMSE "
            f"{fmt_number(before.rmse, 3)} -> {fmt_number(after.rmse, 3)} A) and the charge error goes from "
            f"{fmt_pct(before.error_pct)} % to {fmt_pct(after.error_pct)} %")
    if abs(after.error_pct) > abs(before.error_pct):
        text += ": the whole-run charge gets worse, the correction fits the current's shape, not its total"
    return text + "."


def _confusions(stage: Stage) -> list[str]:
    """Which candidates the power data hardly tell from the first chosen effect (alone, within
    :data:`CONFUSED_FRACTION` of its shrink), and which they do."""
    first = stage.score(stage.chosen[0])
    out = []
    for s in stage.ranking:
        if s.name == first.name or first.shrink_pct <= 0:
            continue
        pair = frozenset((s.name, first.name))
        if s.shrink_pct >= CONFUSED_FRACTION * first.shrink_pct:
            out.append(f"{s.name} alone explains {fmt_number(s.shrink_pct, 3)} % of the squared power gap, close to "
                       f"{first.name}'s {fmt_number(first.shrink_pct, 3)} %: these data hardly tell them apart "
                       f"({_SEPARATES.get(pair, 'other manoeuvres may separate them')}).")
        else:
            out.append(f"{first.name} is told apart from {s.name}: {s.name} alone explains only "
                       f"{fmt_number(s.shrink_pct, 3)} % (against {fmt_number(first.shrink_pct, 3)} %).")
    return out


def stage_verdict(stage: Stage, settings: FitSettings, *, localisation: Sequence[GapShare] = (),
                  ties: Sequence[Tie] = (), drives: Sequence[Any] = ()) -> tuple[str, ...]:
    """Plain sentences on a stage: how large its gap is, what explains it, how far it shrinks, what the data
    cannot tell apart.

    ``localisation`` (the current's slices) names the largest slice; ``ties`` and ``drives`` (the
    current stage's :class:`Tie` and their separating drives) follow the effect they tie.
    """
    held = settings.held
    out = [_opening(stage, localisation)]
    by_name = {s.name: s for s in stage.ranking}
    if not any(by_name[n].kind != "learned" for n in stage.chosen):
        if stage.quantity is POWER:
            return (*out, "No unmodelled electrical effect found: no electrical candidate ("
                    + ", ".join(s.name for s in stage.ranking) + ") shrinks the held-out power gap significantly.")
        out.append("No unmodelled effect found: no catalogued effect shrinks the held-out gap significantly.")
    for k, n in enumerate(stage.chosen):
        s = by_name[n]
        out.append(_effect_sentence(stage, k, s, held))
        tie = next((t for t in ties if t.chosen == n), None)
        if tie is not None:
            out.append(tie.sentence())
            out.extend(d.sentence() for d in drives if d.effects[0] == n)
        if stage.quantity is CURRENT and s.kind != "learned" and s.doubtful:
            out.append(_doubt_sentence(stage, s))
    if stage.chosen:
        out.append(_closing(stage, held))
    if stage.quantity is POWER:
        out += _confusions(stage)
    return tuple(out)


# ---------------------------------------------------------------------- the power stage
def _corrected(basis: PhysicsBasis, chosen: Sequence[Effect], values: Sequence[np.ndarray]) -> tuple[Any, tuple[str, ...]]:
    rb = basis.robot
    for e, v in zip(chosen, values):
        vals = e.values_dict(v)
        if e.name == "armature_heat":
            rb = rb.replace(motor=dataclasses.replace(rb.motor, armature_resistance_ohm=vals["armature_resistance_ohm"]))
        else:
            rb = rb.replace(**vals)
    effects = tuple(dict.fromkeys(tuple(basis.effects) + tuple(e.name for e in chosen)))
    return rb, effects


def power_stage(data: DiagnosisData, candidates: Sequence[Effect], settings: FitSettings, *, client: Any = None,
                progress: bool = False) -> Stage:
    """The power stage on the prepared battery-power data (:func:`~energy.diagnosis.case.diagnosis_case`).

    Measured: voltage x pack current of every log. Predicted: the model's electrical basis from
    the measured drive currents (:mod:`energy.diagnosis.power_data`). ``candidates``: electrical
    effects bound to the logs; the split is the current stage's. Nothing is scored on the data
    it was fitted on.

    Raises
    ------
    DataError
        A fold with fewer values than a set has parameters.
    """
    runner = SetRunner(data, client=client, progress=progress)
    sel = select_effects(list(candidates), runner, settings.n_bootstrap, settings.seed)
    values = fit_effect_set(list(sel.chosen), data) if sel.chosen else []
    robot_out, effects_out = _corrected(data.basis, sel.chosen, values)
    stage = stage_of(POWER, data, sel, settings,
                     fitted={e.name: e.values_dict(v) for e, v in zip(sel.chosen, values)},
                     corrected_robot=robot_out, corrected_effects=effects_out)
    return dataclasses.replace(stage, verdict=stage_verdict(stage, settings))
