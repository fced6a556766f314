"""``diagnose``: where a current model's gap lies, which catalogued effect causes it, how far it shrinks."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from terrawatt_base.checks import check_instance, fmt_number
from terrawatt_base.dask_client import Compute

from ..logs import InteractionLog
from ..models.base import CurrentModel
from .case import DiagnosisCase, DiagnosisData, FitSettings, diagnosis_case
from .corrected import CorrectedCurrentModel
from .effect_base import Effect
from .effects import NOT_IDENTIFIABLE_FROM_CURRENT
from .fit import SetRunner, SetScore, score_effect_set
from .gap import CURRENT, localise_gap
from .model_source import ModelUnderDiagnosis
from .noise import residual_noise
from .report import Diagnosis
from .result import Tie
from .selection import (
    SIGNIFICANT_SHRINK_PCT,
    Selection,
    score_entry,
    select_effects,
    shrink_pct,
    significant,
    unit_gain_interval,
    units_needed,
)
from .separating import SeparatingDrive, separating_drive
from .stage import Stage, power_stage, stage_of, stage_verdict

__all__ = ["SIGNIFICANT_SHRINK_PCT", "diagnose"]


def _corrected(case: DiagnosisCase, effects: Sequence[Effect]) -> CorrectedCurrentModel:
    """The model with ``effects`` added, fitted on all logs."""
    return CorrectedCurrentModel(case.model, list(effects), case.robot, case.terrain).fit(case.logs)


def diagnose(model: CurrentModel | ModelUnderDiagnosis, logs: InteractionLog | Sequence[InteractionLog], *,
             terrain: Any = None, effects: Sequence[Any] | None = None, settings: FitSettings | None = None,
             robot: Any = None, compute: Compute | None = None) -> Diagnosis:
    """Diagnose the gap between a current model and logged currents.

    Every candidate effect (the catalogue, or ``effects``) that the model lacks is fitted on
    the calibration part of each fold and scored on its held-out part (other runs with
    ``settings.split="runs"``; contiguous blocks of each run with ``"blocks"``); candidates are
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
    model : CurrentModel or ModelUnderDiagnosis
        A fitted current model (physics, estimator, baselines), or one with where it comes from
        (:func:`~energy.diagnosis.model_under_diagnosis`: its note heads the report, its robot is
        the reference physics).
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
    settings : FitSettings, optional
        The split, number of blocks, bootstrap seed and resamples, section length (default
        ``FitSettings()``: runs, 5 blocks, seed 0, 8 s, 200 resamples).
    robot : str, path or RobotParams, optional
        Robot of the reference physics for a model that is not a physics model: a preset name,
        a robot file or a RobotParams (:func:`energy.params.robot_params`); a
        ModelUnderDiagnosis brings its own.
    compute : Compute, optional
        Where the candidate sets are scored and whether a bar shows per batch of them
        (:class:`terrawatt_base.dask_client.Compute`; on dask the data go to each worker once; the
        result equals the serial one).

    Returns
    -------
    Diagnosis

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel, bad logs, settings that are not a FitSettings, an effect that is
        neither a name nor an Effect, not a ``Compute``, a ``robot`` beside a ModelUnderDiagnosis; an
        unreachable scheduler.
    OptionalDependencyError
        A cluster asked for without dask.distributed installed.
    NotFittedError
        An unfitted model.
    UnknownNameError
        An effect name not in the catalogue.
    DataError
        Logs without currents, a model that cannot predict the logs, a split that leaves no
        held-out data, fewer calibration samples than an effect has parameters, a battery
        voltage <= 0 where a pack current is logged.
    """
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    case = diagnosis_case(model, logs, terrain=terrain, effects=effects, settings=settings, robot=robot)
    settings = case.settings
    power = None
    with compute.session() as (client, _):
        if case.power is not None:
            power = power_stage(case.power, case.power_candidates, settings, client=client, progress=compute.progress)
        runner = SetRunner(case.data, client=client, progress=compute.progress)
        sel, final, learned_note = _select(case, runner)

    localisation = localise_gap(case.logs, case.predictions, terrain=case.terrain, section_s=settings.section_s)
    ties = _ties(sel, case.data)
    drives = _separating_drives(case, sel, ties)
    more = _more_data(case, sel) if not sel.chosen else {}
    current = stage_of(CURRENT, case.data, final, settings, skipped=case.skipped)
    current = dataclasses.replace(current, verdict=stage_verdict(current, settings, localisation=localisation,
                                                                 ties=ties, drives=drives))
    verdict = [*current.verdict, *_closing_sentences(power, case.skipped)]
    for sentence in (more.get("sentence"), learned_note):  # the learned note first, then the more-data one
        if sentence is not None:
            verdict.insert(2, sentence)
    return Diagnosis(current, localisation, tuple(verdict), _corrected(case, final.chosen), settings, power, case.note,
                     ties, drives, more, tuple(case.logs), case.terrain)


def _closing_sentences(power: Stage | None, skipped: dict[str, str]) -> list[str]:
    """The verdict after the current stage's sentences: the power stage's (or what current logs cannot show), then
    the candidates these data could not score."""
    out = list(power.verdict) if power is not None else [
        "Not identifiable from current logs (they change power, not current): "
        + ", ".join(NOT_IDENTIFIABLE_FROM_CURRENT) + "."]
    data_bound = {n: w for n, w in skipped.items() if "already" not in w}
    if data_bound:
        out.append("Not scored on these data: " + "; ".join(f"{n} ({w})" for n, w in data_bound.items()) + ".")
    return out


def _select(case: DiagnosisCase, runner: SetRunner) -> tuple[Selection, Selection, str | None]:
    """Rank and add greedily (:func:`select_effects`); where nothing is significant, score the learned correction.

    Returns the selection of the catalogued effects, the final one (the learned correction ranked, and chosen
    only when ``case.learned_requested``: it was named among the candidates) and the verdict's note on the learned
    correction when it would explain the gap but was not asked for (else None)."""
    s, learned = case.settings, case.learned
    sel = select_effects(case.candidates, runner, s.n_bootstrap, s.seed)
    if sel.chosen or learned is None:
        return sel, sel, None
    trial = score_effect_set([learned], case.data)
    entry = score_entry(learned, sel.none, trial, sel.none, trial, s.n_bootstrap, s.seed)
    ranked = dataclasses.replace(sel, scores={**sel.scores, learned.name: entry}, order=(*sel.order, learned))
    if not significant(sel.none, trial, sel.none, s.n_bootstrap, s.seed):
        return sel, ranked, None
    if case.learned_requested:
        return sel, dataclasses.replace(ranked, chosen=(learned,), sets=(*sel.sets, trial),
                                        order=(learned, *sel.order)), None
    lo, hi = entry.shrink_interval_pct
    return sel, ranked, (f"A learned residual correction (not physics) would explain {fmt_number(entry.shrink_pct, 3)} "
                         f"% of the squared current gap (95 % interval {fmt_number(lo, 3)} … {fmt_number(hi, 3)} %); "
                         "it is not added to the corrected model unless asked for (effects=[..., "
                         "'learned_residual']).")


def _separating_drives(case: DiagnosisCase, sel: Selection, ties: Sequence[Tie]) -> tuple[SeparatingDrive, ...]:
    """Per tie, the drive that tells its fitted explanations apart (:func:`separating_drive`), within
    :data:`DRIVE_LIMIT_SHARE` of the robot's limits (:func:`_drive_limits`), with as many runs as the
    split's units need to order the pair."""
    by_name = {e.name: e for e in sel.order}
    n_units = case.split.n_units  # the units the split resamples, and how many a run adds (1, or its blocks)
    units = {"n_units": int(n_units), "units_per_run": max(int(round(n_units / max(len(case.logs), 1))), 1)}
    out = []
    for tie in ties:
        k = sel.chosen.index(by_name[tie.chosen])
        base = list(sel.chosen[:k])
        models = {n: _corrected(case, base + [by_name[n]]) for n in tie.effects}
        drive = _drive(case, tie.effects, models, sel.trials[k][tie.chosen], _corrected(case, base), **units)
        if drive is not None:
            out.append(drive)
    return tuple(out)


def _drive(case: DiagnosisCase, effects: Sequence[str], models: dict[str, Any], current: SetScore, base: Any,
           **units: int) -> SeparatingDrive | None:
    """The drive that tells the fitted model of ``effects[0]`` from the others' (:func:`separating_drive`) against
    the noise of the runs' held-out residual under ``current``, within :func:`_drive_limits`."""
    noise = residual_noise(case.data.measured, current.held_out_a, case.logs)
    return separating_drive(effects, models, case.logs[0], noise, *_drive_limits(case), base=base, terrain=case.terrain,
                            **units)


#: A test drive stays within this share of the robot's top speed and yaw rate.
DRIVE_LIMIT_SHARE = 0.8


def _drive_limits(case: DiagnosisCase) -> tuple[float, float, float]:
    """Speed, yaw rate and acceleration a test drive may use: :data:`DRIVE_LIMIT_SHARE` of the robot's
    top speed and yaw rate (where the explanations differ most is often where the runs never went:
    a gain and an offset agree at the one current the runs drew), and the runs' own hard starts
    (the 95th percentile of their accelerations)."""
    basis = case.data.basis
    vmax = DRIVE_LIMIT_SHARE * basis.robot.max_speed_mps
    wmax = DRIVE_LIMIT_SHARE * basis.robot.max_omega_radps
    accel = np.concatenate([np.abs(np.gradient(log.v_mps, log.time_s)) for log in case.logs if len(log) > 2]
                           or [np.zeros(1)])
    return vmax, wmax, float(np.percentile(accel, 95))


def _more_data(case: DiagnosisCase, sel: Selection) -> dict[str, Any]:
    """Where nothing is significant: how many more runs (or blocks) like these would make the likeliest
    candidate so (:func:`units_needed`), and the test drive that would show it with fewer."""
    top = next((e for e in sel.order if e.kind != "learned"), None)
    if top is None:
        return {}
    sp = case.split
    unit = "runs" if sp.kind == "runs" else "blocks"
    trial = sel.alone[top.name]
    mean, sd, need = units_needed(sel.none, sel.none, trial)
    words = top.describe(trial.median_values()[-1], case.data.prepared.get(top.name, ()))
    out: dict[str, Any] = {"effect": top.name, "explanation": words, "units": unit, "n_units": int(sp.n_units),
                           "mean_gain_pct": mean, "unit_sd_pct": sd, "units_needed": need, "drive": None}
    text = (f"The likeliest candidate, {words}, adds {fmt_number(mean, 3)} points on average over the "
            f"{sp.n_units} {unit} (spread {fmt_number(sd, 3)} points from one to the next)")
    if need is None:
        text += (f": below the {fmt_number(SIGNIFICANT_SHRINK_PCT, 2)} points a finding needs, more {unit} like these "
                 "would not make it one")
    else:
        text += f": about {need} {unit} like these would make it significant at 95 %"
        as_given = _corrected(case, [])
        models = {"as_given": as_given, top.name: _corrected(case, [top])}
        # the candidate as the explanation to confirm, the model as given as the one to beat
        drive = _drive(case, (top.name, "as_given"), models, sel.none, as_given)
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
