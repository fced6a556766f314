"""The separating drive: a short test drive whose currents tell two tied explanations apart.

When the diagnosed runs cannot tell two fitted explanations apart (a :class:`~energy.diagnosis.result.Tie`:
a payload or a turning resistance, a current gain or an offset), a field engineer drives a test
that separates them: straights at constant speed, arcs, pivots, stops and starts, a slope. This
module searches a library of such manoeuvres, within the robot's limits (the explanations often
part where the runs never went: a gain and an offset agree at the one current they drew), for
the one on which the fitted models' predicted currents differ most against what the runs say a
repeat of it would scatter:

- the logs' residual: what the runs' current holds besides the chosen fitted model, per logged
  sample in each sample's turning regime (the sensor's noise and the model's misfit, each run's
  mean removed), and how slowly it varies (its lag-1 autocorrelation ``rho``: correlated
  samples count as ``kappa = (1 + rho) / (1 - rho)`` times fewer; :mod:`energy.diagnosis.noise`);
- the run-to-run spread: the spread of the per-run mean residual beyond what the noise gives
  (``run_spread_a``, a per-run offset that no drive averages away).

With ``d(t)`` the difference of the two predictions over the drive (both sides), a repeat is
scored by projecting its residual against the first model on ``d``: ``T = sum(r d) / sum(d^2)``
is about 0 when the first model is right and 1 when the second is; its standard deviation per
repeat is ``sqrt(kappa sum(d^2 res^2) / sum(d^2)^2 + run_spread^2 ((sum d_L)^2 + (sum d_R)^2) / sum(d^2)^2)``
(sums over the samples the runs' logging rate gives the drive, ``res`` the residual's RMS of
each sample's regime). The separation per repeat ``z = 1 / sd`` is the expected difference over
the whole drive in units of that whole-drive quantity's noise (:attr:`PairSeparation.z_per_repeat`:
"x noise per drive"); deciding at ``T = 0.5`` is right with 95 % probability after
``ceil((2 * 1.645 / z)^2)`` repeats. The expected difference is also given as an RMS current (A)
and per sample in noise units (``RMS(d) / noise_a``, the sensor's white noise alone). Both assume
that one of the fitted models is right up to the residual; where neither is (a misfit both share),
a driven repeat shows a smaller difference than expected: :meth:`SeparatingDrive.score` measures it.

The diagnosis itself orders a tied pair by the runs (:func:`~energy.diagnosis.selection.tied_with`):
the mean lead per run must reach :data:`ORDER_PCT` points of the run's own gap and its 95 %
bootstrap interval (the runs resampled) must clear 0. Where the runs already diagnosed do not order
the pair, that interval clears 0 only once fewer than 2.5 % of the resamples hold none of the
drive's runs, ``(N / (N + n))^(N + n) < 0.025`` for ``N`` runs diagnosed and ``n`` runs of the drive
(4 runs for 6 diagnosed ones, however clear each of them is): :func:`runs_to_order`; and the mean
reaches :data:`ORDER_PCT` once ``n g >= ORDER_PCT (N + n)`` for a drive run's expected lead ``g``
(the diagnosed runs, which do not order the pair, taken to lead by nothing). A drive's
:attr:`SeparatingDrive.repeats` is the largest of these counts.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import write_text_atomic
from terrawatt_base.checks import fmt_number
from terrawatt_base.plot_target import new_figure

from ..commands import CommandProfile
from ..logs import InteractionLog
from ..models.base import log_currents
from ..robot import GRAVITY_MPS2
from .noise import ResidualNoise
from .selection import SIGNIFICANT_SHRINK_PCT

__all__ = ["SeparatingDrive", "DriveCandidate", "PairSeparation", "manoeuvre_library", "separating_drive",
           "drive_log", "slope_drive", "runs_to_order", "REPEAT_Z", "DRIVE_Z", "MAX_DRIVE_S", "MAX_REPEATS", "ORDER_PCT",
           "ORDER_TAIL", "SLOPE_DRIVE"]

#: One-sided 95 % normal quantile: a repeat count is enough when the midpoint decision errs < 5 %.
REPEAT_Z = 1.6448536269514722
#: Longest drive of the library (s), rests included.
MAX_DRIVE_S = 60.0
#: The name of the map's slope drive (:func:`slope_drive`), first among the drives that settle every pair.
SLOPE_DRIVE = "slope"
#: The whole drive's expected difference a drive should reach, in units of that quantity's noise
#: (:attr:`PairSeparation.z_per_repeat`): drives that reach it for every pair rank first.
DRIVE_Z = 3.0
#: A pair that needs more runs of the best drive than this is called equivalent on the library's drives.
MAX_REPEATS = 20
#: Below these the runs never drove / turned: the library holds no manoeuvre that does.
MIN_SPEED_MPS = 0.05
MIN_OMEGA_RADPS = 0.05
#: Points of a unit's gap by which one explanation must lead on average to be ordered (the
#: diagnosis's significance threshold).
ORDER_PCT = SIGNIFICANT_SHRINK_PCT
#: The lower tail of the diagnosis's 95 % bootstrap interval, which must clear 0 for a pair to be ordered.
ORDER_TAIL = 0.025
_REST_S = 2.0
_HOLD_S = 20.0  # a manoeuvre's hold alone (two in a row: half of it each; its long form: twice it)
_SURGE_LOW = 0.3  # surges swing between this share of the stop-and-go speed and that speed
_ACCEL_MPS2 = 0.5  # command ramps: gentle, within any ground robot's limits
_ALPHA_RADPS2 = 1.0


@dataclass(frozen=True)
class PairSeparation:
    """How one manoeuvre separates the chosen explanation from one alternative: the RMS difference
    of their currents (A), the same per sample over the sensor noise's RMS on the drive
    (``noise_units``), the whole drive's difference over that quantity's noise (``z_per_repeat``:
    the residual's correlation and the run-to-run spread counted; module docstring), the runs
    that settle the pair and a run's expected lead in points of its own gap (``lead_pct``, the
    diagnosis's unit; nan without the model the gap is scored against)."""

    difference_rms_a: float
    noise_units: float
    z_per_repeat: float
    repeats: int
    lead_pct: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"difference_rms_a": self.difference_rms_a, "noise_units": self.noise_units,
                "z_per_repeat": self.z_per_repeat, "repeats": self.repeats, "lead_pct": self.lead_pct}


@dataclass(frozen=True)
class DriveCandidate:
    """One manoeuvre of the library, scored against every alternative of a tie."""

    name: str
    description: str
    duration_s: float
    pairs: dict[str, PairSeparation]

    def separable(self, limit: int) -> dict[str, PairSeparation]:
        """The pairs this drive settles within ``limit`` repeats."""
        return {k: v for k, v in self.pairs.items() if v.repeats <= limit}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"name": self.name, "description": self.description, "duration_s": self.duration_s,
                "pairs": {k: v.to_dict() for k, v in self.pairs.items()}}


@dataclass(frozen=True, eq=False)
class SeparatingDrive:
    """The drive that separates tied explanations, with what each predicts on it.

    Attributes
    ----------
    effects : tuple of str
        The chosen effect, then the alternatives it is tied with (for a candidate that is
        not significant: ``("as_given", candidate)``).
    best : DriveCandidate
        The chosen manoeuvre: the largest separation per repeat of its worst separable pair
        (the shorter of equals).
    profile : CommandProfile
        Its commands (v, omega over time), from rest to rest.
    predictions : dict of str to ndarray
        Per effect, the fitted model's predicted (left, right) current (A) over ``profile``.
    noise_a, run_spread_a : float
        The logs' per-sample noise over this drive (its samples' regimes' RMS) and their
        run-to-run spread (:mod:`energy.diagnosis.noise`), A.
    autocorrelation : float
        Lag-1 autocorrelation of the runs' residual (how slowly its misfit varies; informative).
    equivalent : tuple of str
        Alternatives no drive of the library separates from the chosen one within
        :data:`MAX_REPEATS` repeats: on these manoeuvres they are the same explanation.
    library : tuple of DriveCandidate
        Every manoeuvre scored, best first.
    models : dict of str to CurrentModel
        The fitted models (each the diagnosed model with the effects chosen before the tie
        and one of the set), fitted on all the runs.
    """

    effects: tuple[str, ...]
    best: DriveCandidate
    profile: CommandProfile
    predictions: dict[str, np.ndarray]
    noise_a: float
    run_spread_a: float
    autocorrelation: float
    equivalent: tuple[str, ...] = ()
    library: tuple[DriveCandidate, ...] = field(default_factory=tuple)
    models: dict[str, Any] = field(default_factory=dict)
    runs_to_order: int = 1

    @property
    def separated(self) -> dict[str, PairSeparation]:
        """The alternatives this drive separates from the chosen effect, with how."""
        return {k: v for k, v in self.best.pairs.items() if k not in self.equivalent}

    @property
    def repeats(self) -> int:
        """Runs of the drive that settle every separable pair at 95 % (0: none is separable): what its
        matched-filter test needs, and at least what the diagnosis's ordering of the runs needs
        (:attr:`runs_to_order`)."""
        if not self.separated:
            return 0
        return max(max(v.repeats for v in self.separated.values()), self.runs_to_order)

    @property
    def expected_difference_a(self) -> float:
        """The smallest RMS difference (A, both sides) between the chosen model's currents and a separable
        alternative's over the drive (nan: none is separable)."""
        return min((v.difference_rms_a for v in self.separated.values()), default=math.nan)

    @property
    def noise_units(self) -> float:
        """The smallest difference of a separable pair per sample over the noise's RMS on the drive (nan: none)."""
        return min((v.noise_units for v in self.separated.values()), default=math.nan)

    @property
    def drive_noise_units(self) -> float:
        """The smallest separation of a separable pair over the whole drive: its expected difference against the
        noise of that whole-drive quantity (:attr:`PairSeparation.z_per_repeat`; nan: none is separable)."""
        return min((v.z_per_repeat for v in self.separated.values()), default=math.nan)

    @property
    def file_stem(self) -> str:
        """``separating_drive_<chosen>``: the name of its CSV and figure."""
        return f"separating_drive_{self.effects[0]}"

    def sentence(self) -> str:
        """The verdict's sentence: what to drive, how long, the expected differences, the repeats."""
        chosen = self.effects[0]
        out = []
        if self.separated:
            diffs = ", ".join(f"{fmt_number(v.difference_rms_a, 3)} A RMS from {k}" for k, v in self.separated.items())
            n = self.repeats
            out.append(f"To tell {chosen} from {' and '.join(self.separated)}, drive {self.best.description} "
                       f"({fmt_number(self.best.duration_s, 3)} s; {self.file_stem}.csv): the fitted models' currents "
                       f"differ there by {diffs} (the logs' noise is {fmt_number(self.noise_a, 3)} A, the run-to-run "
                       f"spread {fmt_number(self.run_spread_a, 3)} A; over the whole drive "
                       f"{fmt_number(self.drive_noise_units, 3)} x its noise); "
                       f"{'one run of it settles' if n == 1 else f'{n} runs of it settle'} the choice at 95 %.")
        if self.equivalent:
            out.append(f"No drive of the library separates {chosen} from {' or '.join(self.equivalent)} within "
                       f"{MAX_REPEATS} runs: on straights, arcs, pivots and stops they predict the same currents.")
        return " ".join(out)

    def score(self, log: InteractionLog) -> dict[str, dict[str, float]]:
        """How a driven repeat (``log``, with currents) scores, per alternative: the RMS error of the chosen and
        the alternative model, the measured difference ``sqrt(|MSE_alt - MSE_chosen|)`` (comparable with the
        expected ``difference_rms_a``) and the projection ``T`` (about 0: the chosen explanation; about 1: the
        alternative)."""
        chosen = self.effects[0]
        meas = log_currents(log)
        pa = np.asarray(self.models[chosen].predict(log), dtype=float)
        out = {}
        for alt in self.effects[1:]:
            pb = np.asarray(self.models[alt].predict(log), dtype=float)
            mse_a, mse_b = float(np.mean((meas - pa) ** 2)), float(np.mean((meas - pb) ** 2))
            d = pb - pa
            den = float(np.sum(d**2))
            out[alt] = {"rmse_chosen_a": math.sqrt(mse_a), "rmse_alternative_a": math.sqrt(mse_b),
                        "measured_difference_a": math.sqrt(abs(mse_b - mse_a)),
                        "projection": float(np.sum((meas - pa) * d) / den) if den > 0 else math.nan}
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the profile and predictions are in the CSV)."""
        return {"effects": list(self.effects), "drive": self.best.to_dict(), "csv": f"{self.file_stem}.csv",
                "repeats": self.repeats, "expected_difference_a": self.expected_difference_a,
                "noise_units": self.noise_units, "drive_noise_units": self.drive_noise_units, "noise_a": self.noise_a,
                "run_spread_a": self.run_spread_a,
                "autocorrelation": self.autocorrelation, "equivalent": list(self.equivalent),
                "runs_to_order": self.runs_to_order,
                "library": [c.to_dict() for c in self.library]}

    def to_csv(self) -> str:
        """The command profile with every prediction: ``time_s, v_mps, omega_radps`` (what the robot drives)
        then each model's left / right current (A)."""
        names = list(self.predictions)
        head = "time_s,v_mps,omega_radps," + ",".join(f"{n}_left_a,{n}_right_a" for n in names)
        rows = np.column_stack([self.profile.time_s, self.profile.v_mps, self.profile.omega_radps,
                                *(self.predictions[n] for n in names)])
        return head + "\n" + "\n".join(",".join(f"{x:.6g}" for x in r) for r in rows) + "\n"

    def write_csv(self, folder: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_csv` as ``<folder>/<file_stem>.csv`` atomically; return the path."""
        return write_text_atomic(Path(folder) / f"{self.file_stem}.csv", self.to_csv())

    def plot(self, ax: Any = None) -> Any:
        """The commands and the predictions over the drive (matplotlib); returns the figure."""
        if ax is None:
            fig, (ax_cmd, ax) = new_figure((8, 5.5), 2, 1, sharex=True, height_ratios=(1, 2))
        else:
            fig, ax_cmd = ax.figure, None
        t = self.profile.time_s
        if ax_cmd is not None:
            ax_cmd.plot(t, self.profile.v_mps, label="v (m/s)")
            ax_cmd.plot(t, self.profile.omega_radps, label="omega (rad/s)")
            ax_cmd.set_ylabel("command")
            ax_cmd.legend(loc="upper right", fontsize=8)
            ax_cmd.set_title(f"Separating drive: {self.best.description}", fontsize=10)
        colors = ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:brown", "tab:gray")
        for (name, pred), color in zip(self.predictions.items(), colors * 4):
            ax.plot(t, pred[:, 0], "-", color=color, label=f"{name}: left")
            ax.plot(t, pred[:, 1], ":", color=color, lw=2, label=f"{name}: right")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("predicted current (A)")
        ax.set_title(f"smallest difference {fmt_number(self.expected_difference_a, 3)} A RMS = "
                     f"{fmt_number(self.noise_units, 3)} x noise per sample, {fmt_number(self.drive_noise_units, 3)} x "
                     f"per drive; {self.repeats} run(s) for 95 %", fontsize=9)
        ax.legend(fontsize=8, ncol=2)
        fig.tight_layout()
        return fig


def runs_to_order(n_units: int, units_per_run: int = 1, tail: float = ORDER_TAIL) -> int:
    """Runs of a separating drive that let the diagnosis order a pair its ``n_units`` units (runs, or
    blocks) do not: the fewest ``n`` with ``(N / (N + n u))^(N + n u) < tail`` (``u`` units per run),
    so that fewer than ``tail`` of the bootstrap's resamples of the units hold none of the drive's.

    Examples
    --------
    >>> runs_to_order(6), runs_to_order(2), runs_to_order(6, units_per_run=5)
    (4, 3, 1)
    """
    n_units, per = int(n_units), max(int(units_per_run), 1)
    if n_units < 1:
        return 1
    n = 1
    while (n_units / (n_units + n * per)) ** (n_units + n * per) >= tail:
        n += 1
    return n


def _ramp(targets: Sequence[tuple[float, float, float]], dt_s: float, accel_mps2: float = _ACCEL_MPS2) -> CommandProfile:
    """Commands from ``(hold_s, v, omega)`` holds, each reached at a bounded rate, from rest to rest."""
    segments = [(_REST_S, 0.0, 0.0), *targets, (_REST_S, 0.0, 0.0)]
    v_out, w_out = [], []
    v = w = 0.0
    for hold, tv, tw in segments:
        n = max(int(round(hold / dt_s)), 1)
        for _ in range(n):
            v += float(np.clip(tv - v, -accel_mps2 * dt_s, accel_mps2 * dt_s))
            w += float(np.clip(tw - w, -_ALPHA_RADPS2 * dt_s, _ALPHA_RADPS2 * dt_s))
            v_out.append(v)
            w_out.append(w)
    while abs(v) > 1e-12 or abs(w) > 1e-12:  # come back to rest
        v -= float(np.clip(v, -accel_mps2 * dt_s, accel_mps2 * dt_s))
        w -= float(np.clip(w, -_ALPHA_RADPS2 * dt_s, _ALPHA_RADPS2 * dt_s))
        v_out.append(v)
        w_out.append(w)
    t = np.arange(len(v_out)) * dt_s
    return CommandProfile(t, np.array(v_out), np.array(w_out))


def _cycles(hold_s: float, swing_s: float, start_s: float) -> int:
    """Cycles of a swing (``swing_s`` each way, 1.5 s holds) in one and a half ``hold_s`` (at least 2), as many as
    fit in :data:`MAX_DRIVE_S` with the rests and the ramps from and to rest (``start_s``)."""
    cycle = 2 * swing_s + 3.0
    fit = int((MAX_DRIVE_S - 2 * _REST_S - 2 * start_s - 0.5) // cycle)
    return max(min(int(1.5 * hold_s // cycle), fit), 2)


def manoeuvre_library(max_speed_mps: float, max_omega_radps: float, dt_s: float = 0.1,
                      hold_s: float = 20.0, max_accel_mps2: float = _ACCEL_MPS2) -> list[tuple[str, str, CommandProfile]]:
    """The manoeuvres searched: (name, description, commands), each from rest to rest, at most
    :data:`MAX_DRIVE_S`, within ``max_speed_mps`` and ``max_omega_radps``.

    Straights at constant speed (three speeds), arcs (four radii), pivots (two yaw rates, left
    then right), stop-and-go cycles (accelerations at ``max_accel_mps2``, at least the gentle
    0.5 m/s² of the other ramps, and stops), surges (the same accelerations between
    :data:`_SURGE_LOW` of the top speed and the top speed, never standing still: a still
    sample next to a start is where a model's breakaway is a guess at the log's rate) and a
    slow creep; ``hold_s`` sets their length (the cycles: as many as fit in one and a half
    ``hold_s``, and in :data:`MAX_DRIVE_S`); none that
    drives (turns) when ``max_speed_mps`` (``max_omega_radps``) is below :data:`MIN_SPEED_MPS`
    (:data:`MIN_OMEGA_RADPS`): runs that never drove (turned) say nothing of it.
    """
    vmax, wmax = float(max_speed_mps), float(max_omega_radps)
    vmax, wmax = (vmax if vmax >= MIN_SPEED_MPS else 0.0), (wmax if wmax >= MIN_OMEGA_RADPS else 0.0)
    out: list[tuple[str, str, CommandProfile]] = []
    if vmax > 0:
        for frac in (0.35, 0.65, 0.95):
            v = frac * vmax
            out.append((f"straight_{v:.2f}", f"a straight at {fmt_number(v, 2)} m/s held {fmt_number(hold_s, 2)} s",
                        _ramp([(hold_s, v, 0.0)], dt_s)))
        if wmax > 0:
            for radius in (0.5, 1.0, 2.0, 4.0):
                v = min(0.6 * vmax, 0.9 * wmax * radius)
                w = v / radius
                out.append((f"arc_{radius:g}m", f"arcs of {fmt_number(radius, 2)} m radius at {fmt_number(v, 2)} m/s, "
                            f"{fmt_number(hold_s / 2, 2)} s left then right",
                            _ramp([(hold_s / 2, v, w), (hold_s / 2, v, -w)], dt_s)))
        go = 0.8 * vmax
        accel = max(float(max_accel_mps2), _ACCEL_MPS2)  # the starts as hard as the runs' (gentle at least)
        ramp = go / accel
        cycles = _cycles(hold_s, ramp, go / accel)
        out.append(("stop_and_go", f"{cycles} stops and starts to {fmt_number(go, 2)} m/s at "
                    f"{fmt_number(accel, 2)} m/s² (1.5 s holds)",
                    _ramp([(ramp + 1.5, go, 0.0), (ramp + 1.5, 0.0, 0.0)] * cycles, dt_s, accel)))
        low = _SURGE_LOW * go  # the same accelerations without standing still in between
        swing = (go - low) / accel
        cycles = _cycles(hold_s, swing, go / accel)
        out.append(("surges", f"{cycles} surges from {fmt_number(low, 2)} to {fmt_number(go, 2)} m/s and back at "
                    f"{fmt_number(accel, 2)} m/s² (1.5 s holds), without stopping",
                    _ramp([(swing + 1.5, go, 0.0), (swing + 1.5, low, 0.0)] * cycles, dt_s, accel)))
        out.append(("creep", f"a creep at {fmt_number(0.1 * vmax, 2)} m/s held {fmt_number(hold_s, 2)} s",
                    _ramp([(hold_s, 0.1 * vmax, 0.0)], dt_s)))
    if wmax > 0:
        for frac in (0.5, 0.95):
            w = frac * wmax
            out.append((f"pivot_{w:.2f}", f"pivots at {fmt_number(w, 2)} rad/s, {fmt_number(hold_s / 2, 2)} s left "
                        "then right", _ramp([(hold_s / 2, 0.0, w), (hold_s / 2, 0.0, -w)], dt_s)))
    return [m for m in out if m[2].duration_s <= MAX_DRIVE_S + 1e-9]


def _integrated_pose(profile: CommandProfile, start: tuple[float, float, float]) -> np.ndarray:
    """The pose (x, y, heading) of ``profile`` driven as commanded from ``start``."""
    t = profile.time_s
    heading = start[2] + np.concatenate([[0.0], np.cumsum(0.5 * (profile.omega_radps[1:] + profile.omega_radps[:-1])
                                                          * np.diff(t))])
    ds = np.concatenate([[0.0], 0.5 * (profile.v_mps[1:] + profile.v_mps[:-1]) * np.diff(t)])
    return np.column_stack([start[0] + np.cumsum(ds * np.cos(heading)), start[1] + np.cumsum(ds * np.sin(heading)),
                            heading])


def slope_drive(terrain: Any, max_speed_mps: float, dt_s: float = 0.1,
                max_slope_rad: float = math.radians(20.0)) -> tuple[str, str, CommandProfile] | None:
    """Up and back down the steepest straight of ``terrain`` the robot may drive, within a minute.

    Among the free cells no steeper than ``max_slope_rad``, the steepest whose straight along the
    uphill direction (up to 10 m, and half the map's smaller side) stays on free cells of the map;
    driven up at half of ``max_speed_mps``, a 2 s stop, then back down in reverse. The commands
    carry their pose on the map (the models read the slope under it). None when the map is level
    or no such straight exists.
    """
    slope = np.asarray(terrain["slope"])
    free = ~np.asarray(terrain.obstacle) & (slope <= max_slope_rad) & np.isfinite(slope)
    if not free.any() or float(np.max(np.where(free, slope, 0.0))) < math.radians(1.0) or max_speed_mps <= 0:
        return None
    v = 0.5 * float(max_speed_mps)
    rows, cols = slope.shape
    length = min(10.0, 0.5 * min(rows, cols) * terrain.cell_size_m,
                 v * (MAX_DRIVE_S - 2 * _REST_S - 2.0 - 4 * v / _ACCEL_MPS2) / 2.0)
    gx, gy = np.asarray(terrain["grad_x"]), np.asarray(terrain["grad_y"])
    order = np.argsort(np.where(free, slope, -1.0), axis=None)[::-1][:200]
    for idx in order:
        r, c = np.unravel_index(idx, slope.shape)
        if not free[r, c] or slope[r, c] < math.radians(1.0):
            break
        ux, uy = float(gx[r, c]), float(gy[r, c])
        norm = math.hypot(ux, uy)
        ux, uy = ux / norm, uy / norm
        x, y = terrain.xy(r, c)
        s = np.linspace(-length / 2, length / 2, max(int(length / (0.5 * terrain.cell_size_m)), 2))
        px, py = x + s * ux, y + s * uy
        if not np.all(terrain.contains(px, py)):
            continue
        pr, pc = terrain.rowcol(px, py)
        if not np.all(free[pr, pc]):
            continue
        hold = length / v
        profile = _ramp([(hold, v, 0.0), (2.0, 0.0, 0.0), (hold, -v, 0.0)], dt_s)
        heading = math.atan2(uy, ux)
        pose = _integrated_pose(profile, (float(px[0]), float(py[0]), heading))
        grade = math.degrees(float(slope[r, c]))
        text = (f"up and back down the {fmt_number(grade, 2)}° slope at ({fmt_number(float(x), 4)}, "
                f"{fmt_number(float(y), 4)}) m, {fmt_number(length, 2)} m each way at {fmt_number(v, 2)} m/s")
        return (SLOPE_DRIVE, text, CommandProfile(profile.time_s, profile.v_mps, profile.omega_radps, pose))
    return None


def drive_log(profile: CommandProfile, like: InteractionLog) -> InteractionLog:
    """A log of ``profile`` driven as commanded (no currents), with the conventions of ``like``: its
    velocity source and track width, its ground label, a level IMU (gravity alone, gyro = omega);
    its pose is the profile's (a drive placed on a map), else none (level ground wherever it is)."""
    t = profile.time_s
    ta = np.arange(0.0, float(t[-1]) + 1e-9, 0.01)
    pose = profile.pose_xyh  # on a map (the slope drive), or none: the manoeuvre is driven on level ground
    ground = None
    if like.ground is not None and len(like.ground):
        labels, counts = np.unique(np.asarray(like.ground, dtype=str), return_counts=True)
        ground = np.full(t.size, labels[np.argmax(counts)])
    return InteractionLog(t, profile.v_mps, profile.omega_radps, None, None, ta, np.full(ta.size, GRAVITY_MPS2),
                          pose_xyh=pose, ground=ground, meta=replace(like.meta, source="separating drive", notes=""),
                          gyro_z_radps=np.interp(ta, t, profile.omega_radps))


def separating_drive(effects: Sequence[str], models: dict[str, Any], like: InteractionLog, noise: ResidualNoise,
                     max_speed_mps: float, max_omega_radps: float, max_accel_mps2: float = _ACCEL_MPS2, *,
                     base: Any = None, terrain: Any = None, n_units: int = 0,
                     units_per_run: int = 1) -> SeparatingDrive | None:
    """Search the library (:func:`manoeuvre_library`, each manoeuvre alone and each two in a row
    within :data:`MAX_DRIVE_S`; with a ``terrain`` map, also :func:`slope_drive`) for the drive that
    separates ``effects[0]``'s fitted model from every other one of ``effects``, against the
    runs' ``noise`` (:func:`~energy.diagnosis.noise.residual_noise`, per turning regime).

    The best drive is the one whose predictions differ most against the noise sample by sample
    (its worst pair's RMS difference over the noise's RMS): a difference of several noise units
    at every sample holds even where neither fitted model is exact, where a small difference
    summed over many samples would rest on their being exact — and the residual that
    ``z_per_repeat`` counts is the runs' misfit, not the drive's: on manoeuvres the runs never
    drove the fitted models' misfit is unknown (ranked by ``z_per_repeat`` instead, the payload
    against rolling resistance pair of ``benchmarks/diagnosis_ties.py`` drove where a run's
    measured difference was 0.05 of the expected one). A pair's runs of a drive are what its
    matched-filter test needs at 95 % with the whole drive's noise (module docstring);
    given ``base`` (the model without the step's effect, whose gap the diagnosis scores), a
    drive must also be one run of which tells the pair apart as the diagnosis judges it: the
    chosen model's expected gain over the alternative on it, in points of the run's own gap
    (effect and noise), at least :data:`ORDER_PCT` (a drive that does not is no separating
    drive, however many runs of it). Drives that settle every pair some drive settles within
    :data:`MAX_REPEATS` runs come first (the other pairs are :attr:`SeparatingDrive.equivalent`),
    then those whose whole drive reaches :data:`DRIVE_Z` x its noise for every pair (a manoeuvre of
    20 s that falls short may reach it in its 40 s form), then the map's slope drive
    (:data:`SLOPE_DRIVE`), then the largest difference per sample in noise units, then the shortest.
    The slope goes first among the drives that settle every pair because gravity is the one force of
    the library's drives whose size no fit set (``m g sin(pitch)``, the pitch from the map): what the
    explanations predict on it rests on their own terms, where a level drive's difference rests on
    the model's fitted inertia and rolling coefficient away from where the runs drove (on the
    independent simulator, four runs of stops and starts alone read a payload x1.6 as x1.73 and the
    unloaded robot as x1.09; after four runs up and down its ramp the diagnosis reads x1.61-1.67).
    Its cost: standing on the ramp the motors hold the robot, which the models do not predict (they
    predict their rest level), so there the pairs that are not the truth measure that gap too. ``n_units`` (and ``units_per_run``): the
    units the diagnosis resamples, from which :func:`runs_to_order` and the mean lead the diagnosis asks
    for give the least runs of the drive (0: one run). Returns None when the library holds no drive (runs
    that neither drove nor turned).
    """
    chosen, alts = effects[0], list(effects[1:])
    spread = noise.run_spread_a
    kappa = noise.kappa  # logged samples per independent one of the residual
    dt = 0.1
    f = like.drive_rate_hz * dt  # the noise is per logged sample: logged at the runs' rate, f samples per one here
    scored = []
    for name, text, profile in _drives(max_speed_mps, max_omega_radps, dt, max_accel_mps2, terrain):
        log = drive_log(profile, like)
        preds = {n: np.asarray(models[n].predict(log), dtype=float) for n in effects}
        sigma2 = noise.per_sample(log)[:, None] ** 2  # each sample's sensor noise: its regime's
        res2 = noise.residual_per_sample(log)[:, None] ** 2  # each sample's residual (noise and misfit): its regime's
        gap2 = (float(np.sum((preds[chosen] - np.asarray(base.predict(log), dtype=float)) ** 2))
                if base is not None else math.nan)
        pairs = {}
        for alt in alts:
            d = preds[alt] - preds[chosen]
            ss = float(np.sum(d**2))
            var_t = (kappa * float(np.sum(d**2 * res2)) / (ss**2 * f)
                     + spread**2 * float(np.sum(d.sum(axis=0) ** 2)) / ss**2 if ss > 0 else math.inf)
            z = 1.0 / math.sqrt(var_t) if var_t > 0 else math.inf
            repeats = (max(int(math.ceil((2 * REPEAT_Z / z) ** 2)), 1) if 0 < z < math.inf
                       else (1 if z == math.inf else 10**9))
            gain = math.nan
            if math.isfinite(gap2):
                # a run's gain in points of its own gap, if the chosen model is right up to the noise
                gain = 100.0 * ss / (gap2 + float(np.sum(sigma2)) * d.shape[1]) if ss > 0 else 0.0
                repeats = repeats if gain > ORDER_PCT else 10**9
                if gain > ORDER_PCT and n_units > 0:  # the mean lead over all units must reach ORDER_PCT
                    per = max(int(units_per_run), 1)
                    repeats = max(repeats, int(math.ceil(ORDER_PCT * n_units / (per * (gain - ORDER_PCT)))))
            rms = float(math.sqrt(ss / d.size))
            pairs[alt] = PairSeparation(rms, rms / math.sqrt(float(np.mean(sigma2))) if np.any(sigma2) else math.inf,
                                        z, min(repeats, 10**9), gain)
        scored.append((DriveCandidate(name, text, float(profile.duration_s), pairs), profile, preds,
                       float(np.sqrt(np.mean(sigma2)))))
    if not scored:
        return None
    equivalent = tuple(a for a in alts if min(c[0].pairs[a].repeats for c in scored) > MAX_REPEATS)
    live = [a for a in alts if a not in equivalent] or alts

    def settles(c: DriveCandidate) -> bool:
        return all(c.pairs[a].repeats <= MAX_REPEATS for a in live)

    def clearest(c: DriveCandidate) -> float:  # the worst pair's difference per sample, in noise units
        return min(c.pairs[a].noise_units for a in live)

    def clear_per_drive(c: DriveCandidate) -> bool:  # every pair's whole drive >= DRIVE_Z x its noise
        return all(c.pairs[a].z_per_repeat >= DRIVE_Z for a in live)

    # drives that settle every separable pair, then those DRIVE_Z x the noise per drive, then the map's slope
    # (gravity: a force no fit sized), then the largest difference per sample, then the shortest
    scored.sort(key=lambda c: (not settles(c[0]), not clear_per_drive(c[0]), c[0].name != SLOPE_DRIVE,
                               -clearest(c[0]), c[0].duration_s))
    best, profile, preds, drive_noise = scored[0]
    return SeparatingDrive(tuple(effects), best, profile, preds, drive_noise, float(spread), float(noise.autocorrelation),
                           equivalent, tuple(c[0] for c in scored), {n: models[n] for n in effects},
                           runs_to_order(n_units, units_per_run) if n_units > 0 else 1)


def _drives(max_speed_mps: float, max_omega_radps: float, dt: float, accel: float,
            terrain: Any = None) -> list[tuple[str, str, CommandProfile]]:
    """The library's manoeuvres alone (20 s holds, and 40 s: the longer or more often repeated form, where
    one of 20 s falls short of :data:`DRIVE_Z`) and each two of them in a row (10 s holds) within a
    minute; with a map, its slope drive (alone: it is driven where it is), and every drive placed
    on the map (from its most level free spot near the centre; one that would leave the map or
    cross an obstacle is left out)."""
    single = manoeuvre_library(max_speed_mps, max_omega_radps, dt, max_accel_mps2=accel)
    single += [(f"{name}_long", text, profile) for name, text, profile
               in manoeuvre_library(max_speed_mps, max_omega_radps, dt, hold_s=2 * _HOLD_S, max_accel_mps2=accel)]
    slope = slope_drive(terrain, max_speed_mps, dt) if terrain is not None else None
    if slope is not None:
        single.append(slope)
    half = manoeuvre_library(max_speed_mps, max_omega_radps, dt, hold_s=_HOLD_S / 2, max_accel_mps2=accel)
    out = list(single)
    for i, (na, ta, pa) in enumerate(half):
        for nb, tb, pb in half[i + 1:]:
            if pa.duration_s + pb.duration_s > MAX_DRIVE_S:
                continue
            t = np.concatenate([pa.time_s, pa.time_s[-1] + dt + pb.time_s])
            out.append((f"{na}+{nb}", f"{ta}, then {tb}",
                        CommandProfile(t, np.concatenate([pa.v_mps, pb.v_mps]),
                                       np.concatenate([pa.omega_radps, pb.omega_radps]))))
    if terrain is None:
        return out
    start = _level_start(terrain)
    placed = []
    for name, text, profile in out:  # driven where the map lets it: on the map, off obstacles
        if profile.pose_xyh is None:
            pose = _integrated_pose(profile, start)
            if not _on_free_ground(terrain, pose):
                continue
            profile = CommandProfile(profile.time_s, profile.v_mps, profile.omega_radps, pose)
        placed.append((name, text, profile))
    return placed


def _level_start(terrain: Any) -> tuple[float, float, float]:
    """Where the manoeuvres that are not tied to a place start on a map: the free cell nearest its centre
    among those within 2° of level (else the least steep free cell), heading +x."""
    slope = np.asarray(terrain["slope"])
    free = ~np.asarray(terrain.obstacle) & np.isfinite(slope)
    rows, cols = np.indices(slope.shape)
    centre = ((slope.shape[0] - 1) / 2.0, (slope.shape[1] - 1) / 2.0)
    far = np.hypot(rows - centre[0], cols - centre[1])
    level = free & (slope <= math.radians(2.0))
    score = np.where(level, far, np.inf) if level.any() else np.where(free, slope, np.inf)
    r, c = np.unravel_index(int(np.argmin(score)), slope.shape)
    x, y = terrain.xy(r, c)
    return float(x), float(y), 0.0


def _on_free_ground(terrain: Any, pose: np.ndarray) -> bool:
    """Whether every pose of a drive lies on the map and off its obstacles."""
    x, y = pose[:, 0], pose[:, 1]
    if not np.all(terrain.contains(x, y)):
        return False
    r, c = terrain.rowcol(x, y)
    return not bool(np.any(np.asarray(terrain.obstacle)[r, c]))

