"""The power stage of the diagnosis: explain the battery power beyond what the measured drive currents draw.

Measured: voltage x pack current of every log. Predicted: the model's electrical basis from
the measured drive currents (:mod:`energy.diagnosis.power_data`). The electrical candidates
(:mod:`energy.diagnosis.effects_power`) are fitted on calibration runs or blocks and scored
on held-out ones with the same split, bootstrap and greedy significance rule as the current
stage (:func:`~energy.diagnosis.selection.select_effects`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number, fmt_pct

from ..logs import InteractionLog
from .effect_base import Effect
from .fit import DiagnosisData, SetRunner, SetScore, Split, fit_effect_set, shrink_pct
from .model_currents import PhysicsBasis, physics_basis
from .power_data import check_power_logs, power_inputs, predicted_battery_power_w
from .power_result import PowerDiagnosis, PowerGapSummary, PowerWaterfallStep, power_gap_summary
from .result import EffectScore
from .selection import select_effects

__all__ = ["diagnose_power", "power_verdict"]

# what would separate two electrical effects that the data cannot tell apart
_SEPARATES = {frozenset(("sensor", "control")): "stops, the start-up after a stop or a per-device current separate them",
              frozenset(("sensor", "armature_heat")): "runs of very different drive currents separate them",
              frozenset(("control", "armature_heat")): "runs of very different drive currents separate them"}
#: A candidate whose shrink alone reaches this fraction of the chosen one's is called hard to tell apart from it.
CONFUSED_FRACTION = 0.8


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


def _step(label: str, logs: Sequence[InteractionLog], s: SetScore, none: SetScore, stopped: list[np.ndarray],
          section_s: float) -> tuple[PowerWaterfallStep, PowerGapSummary]:
    g = power_gap_summary(logs, [h[:, 0] for h in s.held_out_a], stopped, section_s=section_s)
    return PowerWaterfallStep(label, g.energy_error_pct, g.section_error_pct, g.rmse_w, shrink_pct(none, s)), g


def power_verdict(before: PowerGapSummary, after: PowerGapSummary, ranking: Sequence[EffectScore],
                  chosen: Sequence[str], split: str) -> tuple[str, ...]:
    """Plain sentences on the battery-power gap: how large, what explains it, what cannot be told apart."""
    held = "held-out runs" if split == "runs" else "held-out blocks"
    out = [f"Battery power (voltage x pack current, in every log): the model's electrical basis, fed the measured "
           f"drive currents, misses {fmt_pct(before.energy_error_pct)} % of the battery energy (RMSE "
           f"{fmt_number(before.rmse_w, 3)} W); {fmt_pct(before.stopped_gap_pct)} % of that gap falls while the "
           f"robot stands still ({fmt_pct(before.stopped_time_pct)} % of the time)."]
    by_name = {s.name: s for s in ranking}
    if not chosen:
        out.append("No unmodelled electrical effect found: no electrical candidate ("
                   + ", ".join(s.name for s in ranking) + ") shrinks the held-out power gap significantly.")
        return tuple(out)
    for k, n in enumerate(chosen):
        s = by_name[n]
        lo, hi = s.added_interval_pct
        params = ", ".join(f"{p} = {fmt_number(v, 4)}" for p, v in s.parameters.items())
        lead = f"{n} (electrical; {params})" if k == 0 else f"Then {n} (electrical; {params}), fitted jointly,"
        out.append(f"{lead} explains {fmt_number(s.added_pct, 3)} % of the squared power gap on {held} (95 % interval "
                   f"{fmt_number(lo, 3)} … {fmt_number(hi, 3)} %).")
    out.append(f"With {', '.join(chosen)} added, the battery-energy error on {held} goes from "
               f"{fmt_pct(before.energy_error_pct)} % to {fmt_pct(after.energy_error_pct)} % (RMSE "
               f"{fmt_number(before.rmse_w, 3)} -> {fmt_number(after.rmse_w, 3)} W).")
    first = by_name[chosen[0]]
    for s in ranking:
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
    return tuple(out)


def diagnose_power(model: Any, logs: Sequence[InteractionLog], candidates: Sequence[Effect], split: Split, *,
                   robot: Any = None, section_s: float = 8.0, n_bootstrap: int = 200, seed: int | None = 0,
                   client: Any = None, progress: bool = False) -> PowerDiagnosis:
    """The power stage on logs that all carry battery voltage and pack current.

    ``candidates``: electrical effects (bound here to the logs and ``robot``); ``split``: the
    current stage's split. Nothing is scored on the data it was fitted on.

    Raises
    ------
    DataError
        A battery voltage <= 0 where a pack current is logged; a fold with fewer values than
        a set has parameters.
    """
    items = list(logs)
    check_power_logs(items)
    basis = physics_basis(model, robot)
    usable = [e.bind(items, None, robot) for e in candidates]
    inputs = [power_inputs(basis, log) for log in items]
    stopped = [i.stopped for i in inputs]
    measured = tuple(np.asarray(log.battery_power_w, dtype=np.float64)[:, None] for log in items)
    base = tuple(predicted_battery_power_w(i)[:, None] for i in inputs)
    prepared = {e.name: tuple(e.prepare(model, log) for log in items) for e in usable}
    data = DiagnosisData(tuple(items), measured, base, False, prepared)
    runner = SetRunner(data, split, client=client, progress=progress)
    try:
        sel = select_effects(usable, data, split, runner, n_bootstrap, seed)
    finally:
        runner.close()
    steps = [_step("as given", items, sel.none, sel.none, stopped, section_s)]
    steps += [_step(f"+ {e.name}", items, s, sel.none, stopped, section_s) for e, s in zip(sel.chosen, sel.sets[1:])]
    ranking = tuple(sel.scores[e.name] for e in sel.order)
    names = tuple(e.name for e in sel.chosen)
    values = fit_effect_set(list(sel.chosen), data) if sel.chosen else []
    fitted = {e.name: e.values_dict(v) for e, v in zip(sel.chosen, values)}
    robot_out, effects_out = _corrected(basis, sel.chosen, values)
    before, after = steps[0][1], steps[-1][1]
    verdict = power_verdict(before, after, ranking, names, split.kind)
    return PowerDiagnosis(before, after, ranking, names, tuple(s for s, _ in steps), verdict, fitted, robot_out,
                          effects_out)
