"""Greedy effect selection on held-out data: how much a set shrinks the gap of another (with bootstrap intervals over
the split's units), rank candidates, add the best while it is significant (any stage)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_int, check_seed

from .effect_base import Effect
from .fit import SetRunner, SetScore, score_effect_set
from .result import EffectScore

__all__ = ["SIGNIFICANT_SHRINK_PCT", "shrink_pct", "bootstrap_shrink_interval_pct", "bootstrap_gain_interval_pct",
           "Selection", "score_entry", "significant", "select_effects",
           "plausible_alternative", "tied_with", "unit_gains", "unit_gain_interval", "units_needed"]

#: An effect is added only when it shrinks the held-out gap by at least this much (points of %).
SIGNIFICANT_SHRINK_PCT = 2.0


def shrink_pct(before: SetScore, after: SetScore) -> float:
    """``100 * (1 - MSE_after / MSE_before)`` over the held-out samples."""
    b = float(before.sse_units.sum())
    return 100.0 * (1.0 - float(after.sse_units.sum()) / b) if b > 0 else 0.0


def bootstrap_shrink_interval_pct(before: SetScore, after: SetScore, *, n_bootstrap: int = 200,
                                  seed: int | None = 0, level: float = 0.95) -> tuple[float, float]:
    """Percentile interval of the held-out shrink, resampling the split's units (runs or blocks)."""
    n_bootstrap = check_int("n_bootstrap", n_bootstrap, low=1)
    rng = np.random.default_rng(check_seed(seed))
    b, a = before.sse_units, after.sse_units
    idx = rng.integers(0, b.size, size=(n_bootstrap, b.size))
    sb = b[idx].sum(axis=1)
    sa = a[idx].sum(axis=1)
    vals = 100.0 * (1.0 - sa / np.where(sb > 0, sb, 1.0))
    tail = (1.0 - level) / 2.0 * 100.0
    return float(np.percentile(vals, tail)), float(np.percentile(vals, 100.0 - tail))


def bootstrap_gain_interval_pct(none: SetScore, current: SetScore, trial: SetScore, *, n_bootstrap: int = 200,
                                seed: int | None = 0, level: float = 0.95) -> tuple[float, float]:
    """Percentile interval of what ``trial`` adds to ``current``, in points of the gap of ``none``.

    The same resampled units (runs or blocks) enter all three sums, so the interval is that of
    ``shrink_pct(none, trial) - shrink_pct(none, current)``.
    """
    n_bootstrap = check_int("n_bootstrap", n_bootstrap, low=1)
    rng = np.random.default_rng(check_seed(seed))
    idx = rng.integers(0, none.sse_units.size, size=(n_bootstrap, none.sse_units.size))
    sn = none.sse_units[idx].sum(axis=1)
    gain = (current.sse_units[idx].sum(axis=1) - trial.sse_units[idx].sum(axis=1)) / np.where(sn > 0, sn, 1.0)
    tail = (1.0 - level) / 2.0 * 100.0
    return float(np.percentile(100.0 * gain, tail)), float(np.percentile(100.0 * gain, 100.0 - tail))


def score_entry(e: Effect, none: SetScore, alone: SetScore, current: SetScore, trial: SetScore, n_bootstrap: int,
                seed: int | None, prepared: Sequence[Any] = ()) -> EffectScore:
    """``e`` alone (``alone`` against ``none``) and added to the chosen set (``trial`` against ``current``).

    The fitted values (medians over the folds of ``trial``) come with their priors (read from
    ``prepared``, the effect's per-log preparation, when given), plausible ranges and flags.
    """
    lo, hi = bootstrap_shrink_interval_pct(none, alone, n_bootstrap=n_bootstrap, seed=seed)
    added = shrink_pct(none, trial) - shrink_pct(none, current)
    interval = bootstrap_gain_interval_pct(none, current, trial, n_bootstrap=n_bootstrap, seed=seed)
    values, alone_values = trial.median_values()[-1], alone.median_values()[-1]
    names = [p.name for p in e.parameters]
    low, high = e.plausible_ranges()
    return EffectScore(e.name, e.kind, e.values_dict(values), shrink_pct(none, alone), (lo, hi), e.n_parameters, added,
                       interval, priors=dict(zip(names, (float(x) for x in e.priors(prepared)))),
                       plausible={n: (float(a), float(b)) for n, a, b in zip(names, low, high)},
                       flags=e.plausibility_flags(values),
                       summary=e.describe(values, prepared),
                       alone_parameters=e.values_dict(alone_values), alone_flags=e.plausibility_flags(alone_values),
                       alone_summary=e.describe(alone_values, prepared))


def significant(current: SetScore, trial: SetScore, none: SetScore, n_bootstrap: int, seed: int | None) -> bool:
    """Whether ``trial`` improves on ``current`` significantly: bootstrap lower bound > 0 and at
    least :data:`SIGNIFICANT_SHRINK_PCT` points of the gap of ``none``."""
    lo, _ = bootstrap_shrink_interval_pct(current, trial, n_bootstrap=n_bootstrap, seed=seed)
    gain = shrink_pct(none, trial) - shrink_pct(none, current)
    return lo > 0.0 and gain >= SIGNIFICANT_SHRINK_PCT


@dataclass(frozen=True, eq=False)
class Selection:
    """The outcome of :func:`select_effects`.

    ``none``: the held-out score of the data as given; ``alone``: each candidate on its own;
    ``chosen`` / ``sets``: the effects added, in order, and the held-out score after each
    (``sets[0]`` is ``none``); ``scores``: every candidate's :class:`EffectScore`; ``order``:
    the chosen ones, then the rest by what they would add (best first); ``ties``: per chosen
    effect, the candidates the data cannot tell from it (:func:`tied_with`), and ``trials``
    the scores of the candidates at that step (the chosen effect's among them).
    """

    none: SetScore
    alone: dict[str, SetScore]
    chosen: tuple[Effect, ...]
    sets: tuple[SetScore, ...]
    scores: dict[str, EffectScore]
    order: tuple[Effect, ...]
    ties: tuple[tuple[Effect, ...], ...] = ()
    trials: tuple[dict[str, SetScore], ...] = ()
    n_bootstrap: int = 200
    seed: int | None = 0


def select_effects(usable: Sequence[Effect], runner: SetRunner, n_bootstrap: int, seed: int | None) -> Selection:
    """Rank ``usable`` by held-out shrink on the runner's data; add greedily (every remaining candidate refitted
    jointly with the chosen ones at each step) while the next one is :func:`significant`. A candidate
    with plausible fitted values that is significant goes before one with implausible values."""
    data = runner.data
    none = score_effect_set([], data)
    alone = dict(zip((e.name for e in usable), runner.score([[e] for e in usable], "candidates alone")))
    chosen: list[Effect] = []
    sets = [none]
    scores: dict[str, EffectScore] = {}
    remaining = list(usable)
    trials = dict(alone)
    ties: list[tuple[Effect, ...]] = []
    step_trials: list[dict[str, SetScore]] = []
    while remaining:
        # every remaining candidate refitted jointly with the chosen ones: the ranking is conditional
        trials = (dict(alone) if not chosen else dict(zip(
            (e.name for e in remaining),
            runner.score([chosen + [e] for e in remaining], f"candidates added to {len(chosen)} chosen"))))
        eligible = [e for e in remaining if not e.negligible(trials[e.name].median_values()[-1])]
        if not eligible:
            break
        best = _likeliest(eligible, trials, sets[-1], none, n_bootstrap, seed)
        if not significant(sets[-1], trials[best.name], none, n_bootstrap, seed):
            break
        scores[best.name] = score_entry(best, none, alone[best.name], sets[-1], trials[best.name], n_bootstrap, seed,
                                        data.prepared.get(best.name, ()))
        ties.append(tied_with(best, eligible, trials, sets[-1], none, n_bootstrap, seed))
        step_trials.append(trials)
        chosen.append(best)
        sets.append(trials[best.name])
        remaining.remove(best)
    remaining.sort(key=lambda e: trials[e.name].sse_units.sum())
    scores.update({e.name: score_entry(e, none, alone[e.name], sets[-1], trials[e.name], n_bootstrap, seed,
                                       data.prepared.get(e.name, ())) for e in remaining})
    return Selection(none, alone, tuple(chosen), tuple(sets), scores, tuple(chosen) + tuple(remaining), tuple(ties),
                     tuple(step_trials), n_bootstrap, seed)


def unit_gains(none: SetScore, worse: SetScore, better: SetScore) -> np.ndarray:
    """Per unit (run or block), what ``better`` gains over ``worse`` in points of that unit's own gap
    (``100 (sse_worse - sse_better) / sse_none``): every run counts alike, a short one too."""
    base = np.where(none.sse_units > 0, none.sse_units, 1.0)
    return 100.0 * (worse.sse_units - better.sse_units) / base


def tied_with(best: Effect, eligible: Sequence[Effect], trials: dict[str, SetScore], current: SetScore,
              none: SetScore, n_bootstrap: int, seed: int | None) -> tuple[Effect, ...]:
    """The candidates these data cannot tell from ``best`` as the next effect.

    A physical candidate (not learned) with plausible fitted values that would itself be
    :func:`significant`, and that the runs do not order below ``best`` by the test that adds an
    effect: per unit (run or block), ``best``'s gain over it in points of that unit's own gap
    (:func:`unit_gains`), whose mean is under :data:`SIGNIFICANT_SHRINK_PCT` (a lead the
    diagnosis would not call significant were it an effect's), or whose 95 % bootstrap
    interval holds 0 (the runs disagree). Pairing cancels the runs' own
    spread (which widens each candidate's interval alone: this is the sharp form of "within the
    top one's interval"); judging per unit lets a short run that separates the two (a
    separating drive) decide, where its share of the whole gap would be small. Ordered by
    held-out fit, best first.
    """
    if best.kind == "learned":
        return ()
    rng_seed = check_seed(seed)
    out: list[Effect] = []
    for alt in sorted(eligible, key=lambda e: trials[e.name].sse_units.sum()):
        if alt.name == best.name or alt.kind == "learned" or alt.plausibility_flags(trials[alt.name].median_values()[-1]):
            continue
        if not significant(current, trials[alt.name], none, n_bootstrap, seed):
            continue
        gains = unit_gains(none, trials[alt.name], trials[best.name])
        mean, lo, _ = _mean_interval(gains, n_bootstrap, rng_seed)
        if mean < SIGNIFICANT_SHRINK_PCT or lo <= 0.0:
            out.append(alt)
    return tuple(out)


def unit_gain_interval(none: SetScore, worse: SetScore, better: SetScore, n_bootstrap: int,
                       seed: int | None) -> tuple[float, float, float]:
    """The mean of :func:`unit_gains` over the units and its 95 % bootstrap interval (units resampled)."""
    return _mean_interval(unit_gains(none, worse, better), n_bootstrap, check_seed(seed))


def _mean_interval(values: np.ndarray, n_bootstrap: int, seed: int | None) -> tuple[float, float, float]:
    rng = np.random.default_rng(seed)
    means = values[rng.integers(0, values.size, size=(n_bootstrap, values.size))].mean(axis=1)
    return float(np.mean(values)), float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))


def _likeliest(eligible: Sequence[Effect], trials: dict[str, SetScore], current: SetScore, none: SetScore,
               n_bootstrap: int, seed: int | None) -> Effect:
    """The candidate to add next: the best held-out fit, unless its fitted values are implausible
    and a candidate with plausible values improves the held-out gap significantly and by at least
    half as much — then the best-fitting of those. An implausible value (a current gain of 1.7, a
    motor constant x1.5) is no explanation while a plausible one explains a comparable part of the
    gap; what it fits beyond it is left to the next steps, which may take it (doubtful)."""
    by_fit = sorted(eligible, key=lambda e: trials[e.name].sse_units.sum())
    best = by_fit[0]
    if not best.plausibility_flags(trials[best.name].median_values()[-1]):
        return best
    gain = shrink_pct(none, trials[best.name]) - shrink_pct(none, current)
    for alt in by_fit[1:]:
        if alt.kind == "learned" or alt.plausibility_flags(trials[alt.name].median_values()[-1]):
            continue
        alt_gain = shrink_pct(none, trials[alt.name]) - shrink_pct(none, current)
        if alt_gain >= 0.5 * gain and significant(current, trials[alt.name], none, n_bootstrap, seed):
            return alt
    return best


def plausible_alternative(doubtful: EffectScore, ranking: Sequence[EffectScore],
                          chosen: Sequence[str] = ()) -> EffectScore | None:
    """The likelier cause of the gap a doubtful effect explains, or None.

    Among the candidates of ``ranking`` other than ``doubtful``, not in ``chosen`` and not
    learned, whose fit on its own has no flags (``alone_flags``), those whose held-out
    shrink alone lies within ``doubtful``'s 95 % interval (``shrink_interval_pct``) explain
    a similar gap with plausible values; the one with the largest shrink is returned.
    """
    lo, hi = doubtful.shrink_interval_pct
    similar = [s for s in ranking if s.name != doubtful.name and s.name not in chosen and s.kind != "learned"
               and not s.alone_flags and lo <= s.shrink_pct <= hi]
    return max(similar, key=lambda s: s.shrink_pct, default=None)


def units_needed(none: SetScore, current: SetScore, trial: SetScore, level_z: float = 1.959963984540054) -> tuple[float, float, int | None]:
    """How many units (runs or blocks) like these would make ``trial``'s gain over ``current`` significant.

    Each unit's own gain ``100 (sse_current - sse_trial) / sse_none`` (points of the gap, on
    that unit) has a mean ``m`` and a spread ``s`` over the units; the bootstrap's lower bound
    clears 0 once ``m > z s / sqrt(n)``, so ``n = ceil((z s / m)^2)`` (at least one more than
    now when it does not yet). Returns ``(m, s, n)``; ``n`` is None when no number of units
    would do: the mean gain is not positive or is below :data:`SIGNIFICANT_SHRINK_PCT`.
    """
    gains = unit_gains(none, current, trial)
    m = float(np.mean(gains))
    s = float(np.std(gains, ddof=1)) if gains.size > 1 else math.inf
    if not (m >= SIGNIFICANT_SHRINK_PCT) or not math.isfinite(s):
        return m, s, None
    n = max(int(math.ceil((level_z * s / m) ** 2)), 2)
    return m, s, max(n, gains.size + 1)
