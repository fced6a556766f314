"""Scores of the adapt protocols: :class:`AdaptScore`, :class:`AdaptRow` and their table (the answer is an
:class:`~energy.evaluation.EvaluationResult`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from terrawatt_base.answer import fmt_fixed, markdown_table
from terrawatt_base.errors import UnknownNameError

__all__ = [
    "ADAPT_PROTOCOLS",
    "ADAPT_FILES",
    "ADAPT_FORMAT_VERSION",
    "TRIGGER_SCHEDULE",
    "AdaptScore",
    "AdaptRow",
    "summarise_adapt_scores",
    "adapt_table",
    "finite_percentile",
]

#: Protocols of an :class:`AdaptScore`: leave one run out per ground (the held-out
#: run's first seconds adapt, its remainder scores) or few-shot on a ground left out of
#: training (one run of it adapts, its other runs score).
ADAPT_PROTOCOLS = ("per_ground", "few_shot")
#: Schedule name of the running-error trigger (the other schedules are ``"<T> s"`` prefixes).
TRIGGER_SCHEDULE = "trigger"
#: The JSON and markdown files :meth:`~energy.evaluation.EvaluationResult.write` writes for the adapt protocols.
ADAPT_FILES = ("adapt.json", "adapt.md")
#: Version of the ``adapt.json`` layout (2: the runs' pack energy, total charge and interval coverage,
#: ``totals`` and ``total_summary``).
ADAPT_FORMAT_VERSION = 2
_ALL = "all"


@dataclass(frozen=True)
class AdaptScore:
    """One run and side scored unadapted, adapted and with the gain baseline, on the same samples.

    ``schedule`` is ``"20 s"`` (adapted once on the first 20 s) or ``"trigger"`` (updated
    whenever the running error exceeded the threshold; ``adapt_s`` is then the start of
    the scored part). For ``"per_ground"`` the scored part is the remainder of the run
    after ``adapt_s``; for ``"few_shot"`` it is a whole other run (``adapt_run``: the run
    adapted on). Errors are % of the true charge (whole-run: absolute), section errors as
    :func:`~energy.metrics.compare_currents`, RMSE in A.
    """

    protocol: str
    ground: str
    run: str
    adapt_run: str
    model: str
    side: str
    schedule: str
    adapt_s: float
    scored_s: float
    n_updates: int
    unadapted_whole_pct: float
    unadapted_section_pct: float
    unadapted_rmse_a: float
    adapted_whole_pct: float
    adapted_section_pct: float
    adapted_rmse_a: float
    gain_whole_pct: float
    gain_section_pct: float
    gain_rmse_a: float

    def __post_init__(self) -> None:
        if self.protocol not in ADAPT_PROTOCOLS:
            raise UnknownNameError(f"AdaptScore.protocol must be one of {ADAPT_PROTOCOLS!r}, got {self.protocol!r}")


@dataclass(frozen=True)
class AdaptRow:
    """A row of the adapt and few-shot tables: medians and 90th percentiles over the (run, side) scores of one protocol,
    ground, model and schedule."""

    protocol: str
    ground: str
    model: str
    schedule: str
    n_values: int
    unadapted_median_pct: float
    unadapted_p90_pct: float
    unadapted_section_median_pct: float
    unadapted_rmse_median_a: float
    adapted_median_pct: float
    adapted_p90_pct: float
    adapted_section_median_pct: float
    adapted_rmse_median_a: float
    gain_median_pct: float
    gain_p90_pct: float
    gain_section_median_pct: float
    gain_rmse_median_a: float
    updates_mean: float


def finite_percentile(values: Sequence[float], q: float) -> float:
    """The ``q``-th percentile of the finite ``values`` (NaN when none is): a cell of the evaluation's tables."""
    arr = np.asarray(values, dtype=np.float64)
    arr = arr[np.isfinite(arr)]
    return float(np.percentile(arr, q)) if arr.size else math.nan


def _summary(protocol: str, ground: str, model: str, schedule: str, rows: list[AdaptScore]) -> AdaptRow:
    def col(name: str) -> list[float]:
        return [getattr(r, name) for r in rows]

    out: dict[str, float] = {}
    for kind in ("unadapted", "adapted", "gain"):
        out[f"{kind}_median_pct"] = finite_percentile(col(f"{kind}_whole_pct"), 50)
        out[f"{kind}_p90_pct"] = finite_percentile(col(f"{kind}_whole_pct"), 90)
        out[f"{kind}_section_median_pct"] = finite_percentile(col(f"{kind}_section_pct"), 50)
        out[f"{kind}_rmse_median_a"] = finite_percentile(col(f"{kind}_rmse_a"), 50)
    return AdaptRow(protocol, ground, model, schedule, len(rows), **out,
                        updates_mean=float(np.mean(col("n_updates"))) if rows else math.nan)


def summarise_adapt_scores(scores: list[AdaptScore] | tuple[AdaptScore, ...]) -> tuple[AdaptRow, ...]:
    """One :class:`AdaptRow` per protocol, ground (then ``"all"``), model and schedule, in first-seen order."""
    keys: dict[tuple[str, str, str, str], list[AdaptScore]] = {}
    for s in scores:
        for g in (s.ground, _ALL):
            keys.setdefault((s.protocol, g, s.model, s.schedule), []).append(s)
    order = sorted(keys, key=lambda k: (ADAPT_PROTOCOLS.index(k[0]), k[1] == _ALL, k[2]))
    return tuple(_summary(*k, keys[k]) for k in order)


def adapt_table(rows: Sequence[AdaptRow]) -> list[str]:
    """The lines of the per-side markdown table of adaptation rows: per protocol, ground, model and schedule,
    unadapted | adapted | gain baseline."""
    def f(*xs: float, nd: int = 1) -> str:
        return " / ".join(fmt_fixed(x, nd) for x in xs)

    header = ["protocol", "ground", "model", "adapt on", "values", "unadapted median / p90 %", "adapted median / p90 %",
              "gain median / p90 %", "sections unadapted / adapted / gain %", "RMSE unadapted / adapted / gain A",
              "updates"]
    return markdown_table(header, ([
        s.protocol, s.ground, s.model, s.schedule, s.n_values, f(s.unadapted_median_pct, s.unadapted_p90_pct),
        f(s.adapted_median_pct, s.adapted_p90_pct), f(s.gain_median_pct, s.gain_p90_pct),
        f(s.unadapted_section_median_pct, s.adapted_section_median_pct, s.gain_section_median_pct),
        f(s.unadapted_rmse_median_a, s.adapted_rmse_median_a, s.gain_rmse_median_a, nd=2), f(s.updates_mean)]
        for s in rows), left=4)
