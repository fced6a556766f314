"""What a diagnosis says of each candidate: its held-out score (:class:`EffectScore`) and its ties (:class:`Tie`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from terrawatt_base.checks import fmt_number

__all__ = ["EffectScore", "Tie"]


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
