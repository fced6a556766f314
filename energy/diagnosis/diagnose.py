"""``diagnose``: where a current model's gap lies, which catalogued effect causes it, how far it shrinks."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_int, check_real, check_seed, fmt_number, fmt_pct
from terrawatt_base.dask_client import check_client
from terrawatt_base.errors import DataError, InvalidParameterError, NotFittedError

from ..logs import InteractionLog
from ..models.base import CurrentModel, check_logs, log_currents
from ..params import robot_spec
from .corrected import CorrectedCurrentModel
from .effect_base import Effect
from .effects import LEARNED_EFFECT, NOT_IDENTIFIABLE_FROM_CURRENT, effect, resolve_effects
from .fit import (
    DiagnosisData,
    SetRunner,
    SetScore,
    Split,
    make_split,
    prepare_data,
    score_effect_set,
    shrink_pct,
)
from .gap import GapShare, GapSummary, gap_summary, largest_slices, localise_gap
from .model_currents import physics_basis
from .power_data import power_logs_missing
from .power_result import PowerDiagnosis
from .power_stage import diagnose_power
from .regimes import check_terrain
from .result import Diagnosis, EffectScore, Tie, WaterfallStep
from .noise import residual_noise
from .separating import SeparatingDrive, separating_drive
from .selection import (
    SIGNIFICANT_SHRINK_PCT,
    Selection,
    plausible_alternative,
    score_entry,
    select_effects,
    significant,
    unit_gain_interval,
    units_needed,
)

__all__ = ["SIGNIFICANT_SHRINK_PCT", "diagnose"]


def _check_model(model: Any, logs: list[InteractionLog]) -> list[np.ndarray]:
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a fitted CurrentModel, got {type(model).__name__!r}")
    if not model.is_fitted:
        raise NotFittedError(f"model {type(model).__name__} is not fitted; fit it (or load a saved one) before diagnosing")
    out = []
    for k, log in enumerate(logs):
        try:
            pred = np.asarray(model.predict(log), dtype=np.float64)
        except (DataError, InvalidParameterError, ValueError, KeyError, AttributeError) as exc:
            raise DataError(f"the {type(model).__name__} cannot predict logs[{k}] ({log.meta.source!r}): {exc}") from exc
        if pred.shape != (len(log), 2) or not np.all(np.isfinite(pred)):
            raise DataError(f"the {type(model).__name__} gives no finite (N, 2) prediction for logs[{k}]")
        out.append(pred)
    return out


def _check_currents(logs: list[InteractionLog]) -> None:
    for k, log in enumerate(logs):
        if len(log) < 2:
            raise DataError(f"logs[{k}] has {len(log)} drive sample(s); the diagnosis needs at least 2 per log")
        if not np.any(log_currents(log)):
            raise DataError(f"logs[{k}] ({log.meta.source!r}) has no drive currents (all zero); "
                            "the diagnosis compares measured and predicted currents")


def _candidates(model: Any, logs: list[InteractionLog], items: list[Effect], effects: Any, terrain: Any,
                robot: Any) -> tuple[list[Effect], Effect | None, dict[str, str]]:
    skipped: dict[str, str] = {}
    usable: list[Effect] = []
    learned: Effect | None = None
    for e in items:
        if not e.applies_to(model):
            skipped[e.name] = "already in the model, or not applicable to it"
            continue
        why = e.unsupported(logs, terrain, model)
        if why:
            skipped[e.name] = why
            continue
        bound = e.bind(logs, terrain, robot)
        if e.name == LEARNED_EFFECT:
            learned = bound
        elif bound.n_parameters:
            usable.append(bound)
    if learned is None and effects is None:
        learned = effect(LEARNED_EFFECT)
    return usable, learned, skipped


def _step(label: str, logs: list[InteractionLog], s: SetScore, none: SetScore, section_s: float) -> WaterfallStep:
    g = gap_summary(logs, list(s.held_out_a), section_s=section_s)
    return WaterfallStep(label, g.charge_error_pct, g.section_error_pct, g.rmse_a, shrink_pct(none, s))


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


def _verdict(before: GapSummary, after: GapSummary, ranking: Sequence[EffectScore], chosen: Sequence[str],
             localisation: Sequence[GapShare], skipped: dict[str, str], split: str,
             power: PowerDiagnosis | None = None, ties: Sequence[Tie] = (),
             drives: Sequence[SeparatingDrive] = ()) -> tuple[str, ...]:
    held = "held-out runs" if split == "runs" else "held-out blocks"
    out = [f"The gap is {fmt_pct(before.charge_error_pct)} % of the charge (RMSE "
           f"{fmt_number(before.rmse_a, 3)} A){_largest_slice_clause(localisation)}."]
    by_name = {s.name: s for s in ranking}
    physical = [n for n in chosen if by_name[n].kind != "learned"]
    if not physical:
        out.append("No unmodelled effect found: no catalogued effect shrinks the held-out gap significantly.")
    for k, n in enumerate(chosen):
        s = by_name[n]
        lo, hi = s.added_interval_pct
        doubt = s.kind != "learned" and s.doubtful
        what = ("A learned residual correction (last resort, not physics)" if s.kind == "learned"
                else f"{n} ({s.kind}{'; doubtful' if doubt else ''})")
        if k == 0:
            out.append(f"{what} explains {fmt_number(s.added_pct, 3)} % of the squared current gap on {held} "
                       f"(95 % interval {fmt_number(lo, 3)} … {fmt_number(hi, 3)} %).")
        else:
            out.append(f"Then {what}, fitted jointly with the effects before it, explains a further "
                       f"{fmt_number(s.added_pct, 3)} points (95 % interval {fmt_number(lo, 3)} … {fmt_number(hi, 3)}; "
                       f"{fmt_number(s.shrink_pct, 3)} % alone).")
        tie = next((t for t in ties if t.chosen == n), None)
        if tie is not None:
            out.append(tie.sentence())
            out.extend(d.sentence() for d in drives if d.effects[0] == n)
        if doubt:
            a_lo, a_hi = s.shrink_interval_pct
            text = f"{n} is doubtful: {'; '.join(s.flags)}."
            alt = plausible_alternative(s, ranking, chosen)
            if alt is not None:
                text += (f" {alt.alone_summary} explains a similar held-out gap with plausible values "
                         f"({fmt_number(alt.shrink_pct, 3)} % alone, within {n}'s 95 % interval "
                         f"{fmt_number(a_lo, 3)} … {fmt_number(a_hi, 3)} %): the likelier cause.")
            else:
                text += (f" No candidate with plausible values explains a similar held-out gap (within {n}'s 95 % "
                         f"interval {fmt_number(a_lo, 3)} … {fmt_number(a_hi, 3)} % alone): {n} may stand in for "
                         "an effect outside the catalogue.")
            out.append(text)
    if chosen:
        shrink = 100.0 * (1.0 - (after.rmse_a / before.rmse_a) ** 2) if before.rmse_a > 0 else 0.0
        text = (f"With {', '.join(chosen)} added, the squared current gap on {held} shrinks by "
                f"{fmt_number(shrink, 3)} % (RMSE {fmt_number(before.rmse_a, 3)} -> {fmt_number(after.rmse_a, 3)} A) "
                f"and the charge error goes from {fmt_pct(before.charge_error_pct)} % to "
                f"{fmt_pct(after.charge_error_pct)} %")
        if abs(after.charge_error_pct) > abs(before.charge_error_pct):
            text += ": the whole-run charge gets worse, the correction fits the current's shape, not its total"
        out.append(text + ".")
    if power is None:
        out.append("Not identifiable from current logs (they change power, not current): "
                   + ", ".join(NOT_IDENTIFIABLE_FROM_CURRENT) + ".")
    else:
        out.extend(power.verdict)
    data_bound = {n: w for n, w in skipped.items() if "already" not in w}
    if data_bound:
        out.append("Not scored on these data: " + "; ".join(f"{n} ({w})" for n, w in data_bound.items()) + ".")
    return tuple(out)


def diagnose(model: CurrentModel, logs: InteractionLog | Sequence[InteractionLog], *, terrain: Any = None,
             effects: Sequence[Any] | None = None, split: str = "runs", n_blocks: int = 5, seed: int | None = 0,
             section_s: float = 8.0, n_bootstrap: int = 200, robot: Any = None, client: Any = None,
             progress: bool = False) -> Diagnosis:
    """Diagnose the gap between a current model and logged currents.

    Every candidate effect (the catalogue, or ``effects``) that the model lacks is fitted on
    the calibration part of each fold and scored on its held-out part (other runs with
    ``split="runs"``; contiguous blocks of each run with ``split="blocks"``); candidates are
    ranked by held-out shrink, then added greedily (the set refitted jointly) while the next
    one improves the held-out gap significantly (bootstrap lower bound > 0 and at least
    :data:`SIGNIFICANT_SHRINK_PCT` points). When no catalogued effect is significant, the
    learned residual correction is scored, labelled as such, and the verdict says what it
    would explain; it is added to the corrected model only when asked for by name
    (``effects=[..., "learned_residual"]``): a correction that is not physics, fitted to the
    very gap it explains, is never slipped in. Nothing is scored on the data it was fitted
    on; the inputs are not modified.

    Parameters
    ----------
    model : CurrentModel
        A fitted current model (physics, estimator, baselines).
    logs : InteractionLog or sequence of InteractionLog
        Runs with measured currents. When every log also carries battery voltage and pack
        current, a power stage explains the battery power beyond what the measured currents
        draw with the electrical candidates (``armature_heat``, ``sensor``, ``control``),
        with the same split, bootstrap and selection rule (:attr:`Diagnosis.power`).
    terrain : TerrainMap, optional
        The map the runs drove on (slope effect, grade and space localisation).
    effects : sequence of str or Effect, optional
        Candidates (default: the whole catalogue but the learned correction, which is then
        scored but never added).
    split : {"runs", "blocks"}
    n_blocks : int
        Folds of runs (at most the number of runs), or blocks per run (>= 2).
    seed : int or None
        Seed of the bootstrap intervals.
    section_s : float
        Section length of the section error and the time localisation (s), > 0.
    n_bootstrap : int
        Bootstrap resamples (>= 1).
    robot : str, path or RobotParams, optional
        Robot of the reference physics for a model that is not a physics model: a preset name,
        a robot file or a RobotParams (:func:`energy.params.robot_params`).
    client : distributed.Client, optional
        Score the candidate sets as tasks on this dask client (the data go to each worker
        once); the result equals the serial one.
    progress : bool
        Show a progress bar per batch of candidate sets.

    Returns
    -------
    Diagnosis

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel, bad logs, bad numbers, an effect that is neither a name nor an
        Effect, a ``client`` that is not a ``distributed.Client``.
    OptionalDependencyError
        A ``client`` without dask.distributed installed.
    NotFittedError
        An unfitted model.
    UnknownNameError
        An effect name not in the catalogue; an unknown split.
    DataError
        Logs without currents, a model that cannot predict the logs, a split that leaves no
        held-out data, fewer calibration samples than an effect has parameters, a battery
        voltage <= 0 where a pack current is logged.
    """
    items = check_logs(logs)
    seed = check_seed(seed)
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    n_bootstrap = check_int("n_bootstrap", n_bootstrap, low=1)
    progress = check_bool("progress", progress)
    check_client(client, "candidate effect sets")
    if robot is not None:
        robot = robot_spec(robot)  # a robot file read once: the corrected model keeps its parameters, not a path
    terrain = check_terrain(terrain)
    _check_currents(items)
    sp = make_split(items, split, n_blocks)
    predictions = _check_model(model, items)
    resolved = resolve_effects(effects)
    electrical = [e for e in resolved if e.kind == "electrical"]
    usable, learned, skipped = _candidates(model, items, [e for e in resolved if e.kind != "electrical"], effects,
                                           terrain, robot)
    power = None
    if electrical and not power_logs_missing(items):
        power = diagnose_power(model, items, electrical, sp, robot=robot, section_s=section_s, n_bootstrap=n_bootstrap,
                               seed=seed, client=client, progress=progress)
    elif electrical and effects is not None:  # asked for by name on logs without battery power
        skipped.update({e.name: e.unsupported(items, terrain) or "" for e in electrical})
    basis = physics_basis(model, robot)
    data = prepare_data(model, items, usable + ([learned] if learned is not None else []), basis)

    runner = SetRunner(data, sp, client=client, progress=progress)
    try:
        return _select(model, items, predictions, terrain, robot, usable, learned, skipped, sp, data, runner,
                       section_s, n_bootstrap, seed, power, learned_requested=effects is not None)
    finally:
        runner.close()


def _select(model: CurrentModel, items: list[InteractionLog], predictions: list[np.ndarray], terrain: Any,
            robot: Any, usable: list[Effect], learned: Effect | None, skipped: dict[str, str], sp: Split,
            data: DiagnosisData, runner: SetRunner, section_s: float, n_bootstrap: int,
            seed: int | None, power: PowerDiagnosis | None = None, *, learned_requested: bool = False) -> Diagnosis:
    """Rank, add greedily, build the waterfall, the verdict and the corrected model (the learned
    correction only when ``learned_requested``: it was named among the candidates)."""
    sel = select_effects(usable, data, sp, runner, n_bootstrap, seed)
    none = sel.none
    chosen, sets, scores, order = list(sel.chosen), list(sel.sets), dict(sel.scores), list(sel.order)
    learned_note = None
    if not chosen and learned is not None:
        s = score_effect_set([learned], data, sp)
        scores[learned.name] = score_entry(learned, none, s, none, s, n_bootstrap, seed)
        order.append(learned)
        if significant(none, s, none, n_bootstrap, seed):
            if learned_requested:
                chosen.append(learned)
                sets.append(s)
                order = [learned] + order[:-1]
            else:
                lo, hi = scores[learned.name].shrink_interval_pct
                learned_note = (f"A learned residual correction (not physics) would explain "
                                f"{fmt_number(scores[learned.name].shrink_pct, 3)} % of the squared current gap "
                                f"(95 % interval {fmt_number(lo, 3)} … {fmt_number(hi, 3)} %); it is not added to the "
                                "corrected model unless asked for (effects=[..., 'learned_residual']).")

    ranking = tuple(scores[e.name] for e in order)
    waterfall = [_step("as given", items, none, none, section_s)]
    waterfall += [_step(f"+ {e.name}", items, s, none, section_s) for e, s in zip(chosen, sets[1:])]
    before = gap_summary(items, list(none.held_out_a), section_s=section_s)
    after = gap_summary(items, list(sets[-1].held_out_a), section_s=section_s)
    localisation = localise_gap(items, predictions, terrain=terrain, section_s=section_s)
    corrected = CorrectedCurrentModel(model, list(chosen), robot, terrain).fit(items)
    names = tuple(e.name for e in chosen)
    ties = _ties(sel, data)
    drives = _separating_drives(sel, ties, data, model, items, robot, terrain, sp)
    more = _more_data(sel, data, model, items, robot, terrain, sp) if not sel.chosen else {}
    verdict = _verdict(before, after, ranking, names, localisation, skipped, sp.kind, power, ties, drives)
    if more:
        verdict = (*verdict[:2], more["sentence"], *verdict[2:])
    if learned_note is not None:
        verdict = (*verdict[:2], learned_note, *verdict[2:])
    return Diagnosis(before, after, localisation, ranking, names, tuple(waterfall), verdict, corrected, skipped, sp.kind,
                     power, ties=ties, separating_drives=drives, more_data=more)


def _separating_drives(sel: Selection, ties: Sequence[Tie], data: DiagnosisData, model: CurrentModel,
                       items: list[InteractionLog], robot: Any, terrain: Any, sp: Split) -> tuple[SeparatingDrive, ...]:
    """Per tie, the drive that tells its fitted explanations apart (:func:`separating_drive`), within
    :data:`DRIVE_LIMIT_SHARE` of the robot's limits (:func:`_drive_limits`), with as many runs as the
    split's units need to order the pair."""
    if not ties:
        return ()
    vmax, wmax, amax = _drive_limits(model, items, robot)
    by_name = {e.name: e for e in sel.order}
    out = []
    for tie in ties:
        k = sel.chosen.index(by_name[tie.chosen])
        base = list(sel.chosen[:k])
        models = {n: CorrectedCurrentModel(model, base + [by_name[n]], robot, terrain).fit(items) for n in tie.effects}
        noise = residual_noise(data.measured, sel.trials[k][tie.chosen].held_out_a, items)
        before = CorrectedCurrentModel(model, base, robot, terrain).fit(items)
        drive = separating_drive(tie.effects, models, items[0], noise, vmax, wmax, amax, base=before, terrain=terrain,
                                 **_units(sp, items))
        if drive is not None:
            out.append(drive)
    return tuple(out)


def _units(sp: Split, items: list[InteractionLog]) -> dict[str, int]:
    """The units the split resamples and how many a run adds (1, or its blocks)."""
    return {"n_units": int(sp.n_units), "units_per_run": max(int(round(sp.n_units / max(len(items), 1))), 1)}


#: A test drive stays within this share of the robot's top speed and yaw rate.
DRIVE_LIMIT_SHARE = 0.8


def _drive_limits(model: CurrentModel, items: list[InteractionLog], robot: Any) -> tuple[float, float, float]:
    """Speed, yaw rate and acceleration a test drive may use: :data:`DRIVE_LIMIT_SHARE` of the robot's
    top speed and yaw rate (where the explanations differ most is often where the runs never went:
    a gain and an offset agree at the one current the runs drew), and the runs' own hard starts
    (the 95th percentile of their accelerations)."""
    basis = physics_basis(model, robot)
    vmax = DRIVE_LIMIT_SHARE * basis.robot.max_speed_mps
    wmax = DRIVE_LIMIT_SHARE * basis.robot.max_omega_radps
    accel = np.concatenate([np.abs(np.gradient(log.v_mps, log.time_s)) for log in items if len(log) > 2] or [np.zeros(1)])
    return vmax, wmax, float(np.percentile(accel, 95))


def _more_data(sel: Selection, data: DiagnosisData, model: CurrentModel, items: list[InteractionLog], robot: Any,
               terrain: Any, sp: Split) -> dict[str, Any]:
    """Where nothing is significant: how many more runs (or blocks) like these would make the likeliest
    candidate so (:func:`units_needed`), and the test drive that would show it with fewer."""
    top = next((e for e in sel.order if e.kind != "learned"), None)
    if top is None:
        return {}
    unit = "runs" if sp.kind == "runs" else "blocks"
    trial = sel.alone[top.name]
    mean, sd, need = units_needed(sel.none, sel.none, trial)
    words = top.describe(trial.median_values()[-1], data.prepared.get(top.name, ()))
    out: dict[str, Any] = {"effect": top.name, "explanation": words, "units": unit, "n_units": int(sp.n_units),
                           "mean_gain_pct": mean, "unit_sd_pct": sd, "units_needed": need, "drive": None}
    text = (f"The likeliest candidate, {words}, adds {fmt_number(mean, 3)} points on average over the "
            f"{sp.n_units} {unit} (spread {fmt_number(sd, 3)} points from one to the next)")
    if need is None:
        text += (f": below the {fmt_number(SIGNIFICANT_SHRINK_PCT, 2)} points a finding needs, more {unit} like these "
                 "would not make it one")
    else:
        text += f": about {need} {unit} like these would make it significant at 95 %"
        vmax, wmax, amax = _drive_limits(model, items, robot)
        as_given = CorrectedCurrentModel(model, [], robot, terrain).fit(items)
        models = {"as_given": as_given, top.name: CorrectedCurrentModel(model, [top], robot, terrain).fit(items)}
        noise = residual_noise(data.measured, sel.none.held_out_a, items)
        # the candidate as the explanation to confirm, the model as given as the one to beat
        drive = separating_drive((top.name, "as_given"), models, items[0], noise, vmax, wmax, amax, base=as_given,
                                 terrain=terrain)
        if drive is not None and drive.separated:
            out["drive"] = {k: v for k, v in drive.to_dict().items() if k != "csv"}  # described, not written
            text += (f", or {drive.repeats} run{'s' if drive.repeats != 1 else ''} of "
                     f"{drive.best.description} ({fmt_number(drive.best.duration_s, 3)} s), where it changes the "
                     f"current by {fmt_number(drive.expected_difference_a, 3)} A RMS")
    out["sentence"] = text + "."
    return out


def _ties(sel: Selection, data: DiagnosisData) -> tuple[Tie, ...]:
    """The :class:`Tie` of each chosen effect whose step the data cannot settle, fitted values as at that step."""
    out = []
    none = sel.none
    for k, (best, alts) in enumerate(zip(sel.chosen, sel.ties)):
        if not alts:
            continue
        trials, current = sel.trials[k], sel.sets[k]

        def added(e: Effect, trials: dict[str, SetScore] = trials, current: SetScore = current) -> float:
            return shrink_pct(none, trials[e.name]) - shrink_pct(none, current)

        words = {e.name: e.describe(trials[e.name].median_values()[-1], data.prepared.get(e.name, ()))
                 for e in (best, *alts)}
        out.append(Tie(best.name, tuple(a.name for a in alts), words, {e.name: added(e) for e in (best, *alts)},
                       {a.name: unit_gain_interval(none, trials[a.name], trials[best.name], sel.n_bootstrap,
                                                   sel.seed)
                        for a in alts}))
    return tuple(out)
