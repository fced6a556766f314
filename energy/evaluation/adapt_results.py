"""Scores of the ``adapt`` protocol: :class:`AdaptScore`, :class:`AdaptSummary`, :class:`AdaptationResult`."""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import check_output_path, json_finite, write_text_atomic
from terrawatt_base.errors import UnknownNameError
from terrawatt_base.formats import result_document, write_result_json

from .run_totals import TOTALS_HEADING, RunTotal, plot_totals_reliability, summarise_totals, totals_markdown


__all__ = [
    "ADAPT_PROTOCOLS",
    "ADAPT_FILES",
    "ADAPT_FORMAT_VERSION",
    "TRIGGER_SCHEDULE",
    "AdaptScore",
    "AdaptSummary",
    "AdaptationResult",
    "summarise_adapt_scores",
    "check_adapt_dir",
]

#: Protocols of an :class:`AdaptationResult`: leave one run out per ground (the held-out
#: run's first seconds adapt, its remainder scores) or few-shot on a ground left out of
#: training (one run of it adapts, its other runs score).
ADAPT_PROTOCOLS = ("per_ground", "few_shot")
#: Schedule name of the running-error trigger (the other schedules are ``"<T> s"`` prefixes).
TRIGGER_SCHEDULE = "trigger"
#: Files :meth:`AdaptationResult.write` writes.
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
class AdaptSummary:
    """Medians and 90th percentiles over the (run, side) scores of one protocol, ground, model and schedule."""

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


def _stat(values: list[float], q: float) -> float:
    arr = np.asarray(values, dtype=np.float64)
    arr = arr[np.isfinite(arr)]
    return float(np.percentile(arr, q)) if arr.size else math.nan


def _summary(protocol: str, ground: str, model: str, schedule: str, rows: list[AdaptScore]) -> AdaptSummary:
    def col(name: str) -> list[float]:
        return [getattr(r, name) for r in rows]

    out: dict[str, float] = {}
    for kind in ("unadapted", "adapted", "gain"):
        out[f"{kind}_median_pct"] = _stat(col(f"{kind}_whole_pct"), 50)
        out[f"{kind}_p90_pct"] = _stat(col(f"{kind}_whole_pct"), 90)
        out[f"{kind}_section_median_pct"] = _stat(col(f"{kind}_section_pct"), 50)
        out[f"{kind}_rmse_median_a"] = _stat(col(f"{kind}_rmse_a"), 50)
    return AdaptSummary(protocol, ground, model, schedule, len(rows), **out,
                        updates_mean=float(np.mean(col("n_updates"))) if rows else math.nan)


def summarise_adapt_scores(scores: list[AdaptScore] | tuple[AdaptScore, ...]) -> tuple[AdaptSummary, ...]:
    """One :class:`AdaptSummary` per protocol, ground (then ``"all"``), model and schedule, in first-seen order."""
    keys: dict[tuple[str, str, str, str], list[AdaptScore]] = {}
    for s in scores:
        for g in (s.ground, _ALL):
            keys.setdefault((s.protocol, g, s.model, s.schedule), []).append(s)
    order = sorted(keys, key=lambda k: (ADAPT_PROTOCOLS.index(k[0]), k[1] == _ALL, k[2]))
    return tuple(_summary(*k, keys[k]) for k in order)


@dataclass(frozen=True)
class AdaptationResult:
    """All scores of :func:`~energy.evaluation.evaluate_adaptation` / :func:`~energy.evaluation.evaluate_few_shot`.

    Attributes
    ----------
    runs : tuple of AdaptScore
    summary : tuple of AdaptSummary
    settings : dict
        The protocol's settings (method, prior, threshold, minimum remainder...).
    skipped : tuple of str
        Runs or grounds left out and why (e.g. a remainder shorter than the minimum).
    totals : tuple of RunTotal
        What the battery pays: per scored run, schedule and variant, the pack energy and
        total charge of both sides, with the forecast's interval
        (:mod:`~energy.evaluation.run_totals`); summarised by :meth:`total_summary`.
    """

    runs: tuple[AdaptScore, ...]
    summary: tuple[AdaptSummary, ...]
    settings: dict[str, Any]
    skipped: tuple[str, ...] = ()
    totals: tuple[RunTotal, ...] = ()

    def total_summary(self) -> list[dict[str, Any]]:
        """Per protocol, ground (then all), model, schedule and variant: pack energy and total charge
        errors (median, p90 %) and the coverage of the 50 / 80 / 95 % intervals
        (:func:`~energy.evaluation.run_totals.summarise_totals`)."""
        return summarise_totals(self.totals)

    def plot_reliability(self, ax: Any = None) -> Any:
        """Observed against nominal coverage of the total-charge intervals per protocol, ground and variant."""
        return plot_totals_reliability(self.totals, ax, title="held-out total charge (both sides)")

    def summary_for(self, protocol: str, ground: str, model: str, schedule: str) -> AdaptSummary:
        """The summary row of one protocol, ground (or ``"all"``), model and schedule.

        Raises
        ------
        UnknownNameError
            No such row.
        """
        for s in self.summary:
            if (s.protocol, s.ground, s.model, s.schedule) == (protocol, ground, model, schedule):
                return s
        raise UnknownNameError(
            f"no adaptation summary for protocol={protocol!r}, ground={ground!r}, model={model!r}, "
            f"schedule={schedule!r}; rows exist for {sorted({(s.protocol, s.ground, s.model, s.schedule) for s in self.summary})!r}"
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form (NaN becomes ``None``), as written to ``adapt.json``."""
        return json_finite(result_document("adaptation", ADAPT_FORMAT_VERSION, {
            "settings": dict(self.settings), "skipped": list(self.skipped),
            "total_summary": self.total_summary(), "summary": [asdict(s) for s in self.summary],
            "totals": [t.to_dict() for t in self.totals], "runs": [asdict(r) for r in self.runs]}))

    def to_markdown(self) -> str:
        """Two markdown tables: what the battery pays (both sides through the pack, total charge and its
        interval's coverage) first, then per side: per protocol, ground, model and schedule, unadapted |
        adapted | gain baseline."""
        def f(x: float, nd: int = 1) -> str:
            return "–" if not math.isfinite(x) else f"{x:.{nd}f}"

        lines = []
        if self.totals:
            lines += [TOTALS_HEADING, "",
                      totals_markdown(self.total_summary()), "Per side (charge of each motor channel):", ""]
        lines += [
            "| protocol | ground | model | adapt on | values | unadapted median / p90 % | adapted median / p90 % | "
            "gain median / p90 % | sections unadapted / adapted / gain % | RMSE unadapted / adapted / gain A | updates |",
            "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for s in self.summary:
            lines.append(
                f"| {s.protocol} | {s.ground} | {s.model} | {s.schedule} | {s.n_values} | "
                f"{f(s.unadapted_median_pct)} / {f(s.unadapted_p90_pct)} | {f(s.adapted_median_pct)} / {f(s.adapted_p90_pct)} | "
                f"{f(s.gain_median_pct)} / {f(s.gain_p90_pct)} | {f(s.unadapted_section_median_pct)} / "
                f"{f(s.adapted_section_median_pct)} / {f(s.gain_section_median_pct)} | {f(s.unadapted_rmse_median_a, 2)} / "
                f"{f(s.adapted_rmse_median_a, 2)} / {f(s.gain_rmse_median_a, 2)} | {f(s.updates_mean)} |"
            )
        if self.skipped:
            lines.append("")
            lines.extend(f"Skipped: {s}" for s in self.skipped)
        return "\n".join(lines) + "\n"

    def write(self, out_dir: str | os.PathLike[str]) -> tuple[Path, Path]:
        """Write ``adapt.json`` and ``adapt.md`` into ``out_dir`` (created if missing), atomically.

        Raises
        ------
        InvalidParameterError
            See :func:`check_adapt_dir`.
        """
        folder = check_adapt_dir(out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        json_name, md_name = ADAPT_FILES
        return (write_result_json(folder / json_name, self.to_dict()),
                write_text_atomic(folder / md_name, self.to_markdown()))


def check_adapt_dir(out_dir: str | os.PathLike[str], name: str = "out_dir") -> Path:
    """Check, before any work, that :meth:`AdaptationResult.write` can write into ``out_dir``.

    Raises
    ------
    InvalidParameterError
        ``out_dir`` is a file, lies under a file, or one of :data:`ADAPT_FILES` in it is a directory.
    """
    folder = check_output_path(out_dir, name, directory=True)
    for file in ADAPT_FILES:
        check_output_path(folder / file, name)
    return folder
