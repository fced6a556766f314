"""The separating drive: a short test drive whose currents tell two tied explanations apart.

When the diagnosed runs cannot tell two fitted explanations apart (a :class:`~energy.diagnosis.result.Tie`:
a payload or a turning resistance, a current gain or an offset), a field engineer drives a test
that separates them: straights at constant speed, arcs, pivots, stops and starts. This module
searches a library of such manoeuvres, each within the speeds and yaw rates the runs themselves
drove (the fitted models are trusted there, not beyond), for the one on which the two fitted
models' predicted currents differ most against what the runs say a repeat of it would scatter:

- the logs' noise: the within-run spread of the chosen model's held-out residual (per sample,
  ``noise_a``), inflated by its lag-1 autocorrelation (correlated samples count less);
- the run-to-run spread: the spread of the per-run mean residual beyond what the noise gives
  (``run_spread_a``, a per-run offset that no drive averages away).

With ``d(t)`` the difference of the two predictions over the drive (both sides), a repeat is
scored by projecting its residual against the first model on ``d``: ``T = sum(r d) / sum(d^2)``
is about 0 when the first model is right and 1 when the second is; its standard deviation per
repeat is ``sqrt(kappa noise^2 / sum(d^2) + run_spread^2 ((sum d_L)^2 + (sum d_R)^2) / sum(d^2)^2)``.
The separation per repeat is ``z = 1 / sd``; deciding at ``T = 0.5`` is right with 95 %
probability after ``ceil((2 * 1.645 / z)^2)`` repeats. The expected difference is also given as
an RMS current (A) and in noise units (``RMS(d) / noise_a``).
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

__all__ = ["SeparatingDrive", "DriveCandidate", "manoeuvre_library", "separating_drive", "residual_noise",
           "REPEAT_Z", "MAX_DRIVE_S"]

#: One-sided 95 % normal quantile: a repeat count is enough when the midpoint decision errs < 5 %.
REPEAT_Z = 1.6448536269514722
#: Longest drive of the library (s), rests included.
MAX_DRIVE_S = 60.0
_REST_S = 2.0
_ACCEL_MPS2 = 0.5  # command ramps: gentle, within any ground robot's limits
_ALPHA_RADPS2 = 1.0
_GRAVITY_MPS2 = 9.80665


@dataclass(frozen=True)
class DriveCandidate:
    """One manoeuvre of the library, scored for a pair of fitted models."""

    name: str
    description: str
    duration_s: float
    difference_rms_a: float
    z_per_repeat: float
    repeats: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"name": self.name, "description": self.description, "duration_s": self.duration_s,
                "difference_rms_a": self.difference_rms_a, "z_per_repeat": self.z_per_repeat,
                "repeats": self.repeats}


@dataclass(frozen=True, eq=False)
class SeparatingDrive:
    """The drive that separates two tied explanations, with what each predicts on it.

    Attributes
    ----------
    effects : (str, str)
        The chosen effect and the alternative it is tied with.
    best : DriveCandidate
        The chosen manoeuvre (largest separation per repeat; the shorter of equals).
    profile : CommandProfile
        Its commands (v, omega over time), from rest to rest.
    predictions : dict of str to ndarray
        Per effect, the fitted model's predicted (left, right) current (A) over ``profile``.
    noise_a, run_spread_a : float
        The logs' per-sample noise and run-to-run spread (module docstring), A.
    autocorrelation : float
        Lag-1 autocorrelation of the residual (the noise's inflation ``(1 + r) / (1 - r)``).
    library : tuple of DriveCandidate
        Every manoeuvre scored, best first.
    models : dict of str to CurrentModel
        The two fitted models (each the diagnosed model with the effects chosen before the tie
        and one of the pair), fitted on all the runs.
    """

    effects: tuple[str, str]
    best: DriveCandidate
    profile: CommandProfile
    predictions: dict[str, np.ndarray]
    noise_a: float
    run_spread_a: float
    autocorrelation: float
    library: tuple[DriveCandidate, ...] = field(default_factory=tuple)
    models: dict[str, Any] = field(default_factory=dict)

    @property
    def expected_difference_a(self) -> float:
        """RMS difference of the two predicted currents over the drive (A, both sides)."""
        return self.best.difference_rms_a

    @property
    def noise_units(self) -> float:
        """:attr:`expected_difference_a` in units of the logs' per-sample noise."""
        return self.expected_difference_a / self.noise_a if self.noise_a > 0 else math.inf

    @property
    def file_stem(self) -> str:
        """``separating_drive_<chosen>_vs_<alternative>``: the name of its CSV and figure."""
        return f"separating_drive_{self.effects[0]}_vs_{self.effects[1]}"

    def sentence(self) -> str:
        """The verdict's sentence: what to drive, how long, the expected difference, the repeats."""
        a, b = self.effects
        return (f"To tell {a} from {b}, drive {self.best.description} ({fmt_number(self.best.duration_s, 3)} s; "
                f"{self.file_stem}.csv): the two fitted models' currents differ there by "
                f"{fmt_number(self.expected_difference_a, 3)} A RMS, {fmt_number(self.noise_units, 3)} x the logs' "
                f"noise of {fmt_number(self.noise_a, 3)} A; "
                f"{'one run of it settles' if self.best.repeats == 1 else f'{self.best.repeats} runs of it settle'} "
                f"the choice at 95 % (run-to-run spread {fmt_number(self.run_spread_a, 3)} A).")

    def score(self, log: InteractionLog) -> dict[str, float]:
        """How a driven repeat (``log``, with currents) scores: each model's RMS error, the measured difference
        ``sqrt(|MSE_b - MSE_a|)`` (comparable with :attr:`expected_difference_a`), and the projection ``T``
        (about 0: the first explanation; about 1: the second)."""
        a, b = self.effects
        meas = log_currents(log)
        pa, pb = (np.asarray(self.models[n].predict(log), dtype=float) for n in (a, b))
        mse_a, mse_b = float(np.mean((meas - pa) ** 2)), float(np.mean((meas - pb) ** 2))
        d = pb - pa
        den = float(np.sum(d**2))
        t = float(np.sum((meas - pa) * d) / den) if den > 0 else math.nan
        return {f"rmse_{a}_a": math.sqrt(mse_a), f"rmse_{b}_a": math.sqrt(mse_b),
                "measured_difference_a": math.sqrt(abs(mse_b - mse_a)), "projection": t}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the profile and predictions are in the CSV)."""
        return {"effects": list(self.effects), "drive": self.best.to_dict(), "csv": f"{self.file_stem}.csv",
                "expected_difference_a": self.expected_difference_a, "noise_units": self.noise_units,
                "noise_a": self.noise_a, "run_spread_a": self.run_spread_a, "autocorrelation": self.autocorrelation,
                "library": [c.to_dict() for c in self.library]}

    def to_csv(self) -> str:
        """The command profile with both predictions: ``time_s, v_mps, omega_radps`` (what the robot drives)
        then each model's left / right current (A)."""
        a, b = self.effects
        pa, pb = self.predictions[a], self.predictions[b]
        head = f"time_s,v_mps,omega_radps,{a}_left_a,{a}_right_a,{b}_left_a,{b}_right_a"
        rows = np.column_stack([self.profile.time_s, self.profile.v_mps, self.profile.omega_radps, pa, pb])
        return head + "\n" + "\n".join(",".join(f"{x:.6g}" for x in r) for r in rows) + "\n"

    def write_csv(self, folder: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_csv` as ``<folder>/<file_stem>.csv`` atomically; return the path."""
        return write_text_atomic(Path(folder) / f"{self.file_stem}.csv", self.to_csv())

    def plot(self, ax: Any = None) -> Any:
        """The commands and the two predictions over the drive (matplotlib); returns the figure."""
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
            ax_cmd.set_title(f"Separating drive: {self.best.description}")
        for (name, pred), color in zip(self.predictions.items(), ("tab:blue", "tab:red")):
            ax.plot(t, pred[:, 0], "-", color=color, label=f"{name}: left")
            ax.plot(t, pred[:, 1], ":", color=color, lw=2, label=f"{name}: right")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("predicted current (A)")
        ax.set_title(f"difference {fmt_number(self.expected_difference_a, 3)} A RMS = "
                     f"{fmt_number(self.noise_units, 3)} x noise; {self.best.repeats} repeat(s) for 95 %", fontsize=9)
        ax.legend(fontsize=8, ncol=2)
        fig.tight_layout()
        return fig


def _ramp(targets: Sequence[tuple[float, float, float]], dt_s: float) -> CommandProfile:
    """Commands from ``(hold_s, v, omega)`` holds, each reached at a bounded rate, from rest to rest."""
    segments = [(_REST_S, 0.0, 0.0), *targets, (_REST_S, 0.0, 0.0)]
    v_out, w_out = [], []
    v = w = 0.0
    for hold, tv, tw in segments:
        n = max(int(round(hold / dt_s)), 1)
        for _ in range(n):
            v += float(np.clip(tv - v, -_ACCEL_MPS2 * dt_s, _ACCEL_MPS2 * dt_s))
            w += float(np.clip(tw - w, -_ALPHA_RADPS2 * dt_s, _ALPHA_RADPS2 * dt_s))
            v_out.append(v)
            w_out.append(w)
    while abs(v) > 1e-12 or abs(w) > 1e-12:  # come back to rest
        v -= float(np.clip(v, -_ACCEL_MPS2 * dt_s, _ACCEL_MPS2 * dt_s))
        w -= float(np.clip(w, -_ALPHA_RADPS2 * dt_s, _ALPHA_RADPS2 * dt_s))
        v_out.append(v)
        w_out.append(w)
    t = np.arange(len(v_out)) * dt_s
    return CommandProfile(t, np.array(v_out), np.array(w_out))


def manoeuvre_library(max_speed_mps: float, max_omega_radps: float, dt_s: float = 0.1,
                      hold_s: float = 20.0) -> list[tuple[str, str, CommandProfile]]:
    """The manoeuvres searched: (name, description, commands), each from rest to rest, at most
    :data:`MAX_DRIVE_S`, within ``max_speed_mps`` and ``max_omega_radps``.

    Straights at constant speed (three speeds), arcs (four radii), pivots (two yaw rates, left
    then right), stop-and-go cycles (accelerations and stops) and a slow creep.
    """
    vmax, wmax = float(max_speed_mps), float(max_omega_radps)
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
        ramp = go / _ACCEL_MPS2
        cycles = max(int((MAX_DRIVE_S - 2 * _REST_S) // (2 * ramp + 3.0)) // 2, 2)
        out.append(("stop_and_go", f"{cycles} stops and starts to {fmt_number(go, 2)} m/s (1.5 s holds)",
                    _ramp([(ramp + 1.5, go, 0.0), (ramp + 1.5, 0.0, 0.0)] * cycles, dt_s)))
        out.append(("creep", f"a creep at {fmt_number(0.1 * vmax, 2)} m/s held {fmt_number(hold_s, 2)} s",
                    _ramp([(hold_s, 0.1 * vmax, 0.0)], dt_s)))
    if wmax > 0:
        for frac in (0.5, 0.95):
            w = frac * wmax
            out.append((f"pivot_{w:.2f}", f"pivots at {fmt_number(w, 2)} rad/s, {fmt_number(hold_s / 2, 2)} s left "
                        "then right", _ramp([(hold_s / 2, 0.0, w), (hold_s / 2, 0.0, -w)], dt_s)))
    return [m for m in out if m[2].duration_s <= MAX_DRIVE_S + 1e-9]


def drive_log(profile: CommandProfile, like: InteractionLog) -> InteractionLog:
    """A log of ``profile`` driven as commanded (no currents), with the conventions of ``like``: its
    velocity source and track width, its ground label, a level IMU (gravity alone, gyro = omega)."""
    t = profile.time_s
    ta = np.arange(0.0, float(t[-1]) + 1e-9, 0.01)
    heading = np.concatenate([[0.0], np.cumsum(0.5 * (profile.omega_radps[1:] + profile.omega_radps[:-1]) * np.diff(t))])
    ds = np.concatenate([[0.0], 0.5 * (profile.v_mps[1:] + profile.v_mps[:-1]) * np.diff(t)])
    pose = np.column_stack([np.cumsum(ds * np.cos(heading)), np.cumsum(ds * np.sin(heading)), heading])
    ground = None
    if like.ground is not None and len(like.ground):
        labels, counts = np.unique(np.asarray(like.ground, dtype=str), return_counts=True)
        ground = np.full(t.size, labels[np.argmax(counts)])
    return InteractionLog(t, profile.v_mps, profile.omega_radps, None, None, ta, np.full(ta.size, _GRAVITY_MPS2),
                          pose_xyh=pose, ground=ground, meta=replace(like.meta, source="separating drive", notes=""),
                          gyro_z_radps=np.interp(ta, t, profile.omega_radps))


def residual_noise(measured: Sequence[np.ndarray], predicted: Sequence[np.ndarray]) -> tuple[float, float, float]:
    """The logs' noise of a model's (held-out) residual: per-sample within-run spread (A), run-to-run
    spread of the per-run mean beyond it (A), lag-1 autocorrelation of the within-run residual."""
    res = [np.asarray(m, float) - np.asarray(p, float) for m, p in zip(measured, predicted)]
    within = [r - r.mean(axis=0) for r in res]
    noise = float(np.sqrt(np.mean(np.concatenate([w.ravel() ** 2 for w in within]))))
    num = sum(float(np.sum(w[1:] * w[:-1])) for w in within if len(w) > 1)
    den = sum(float(np.sum(w**2)) for w in within)
    rho = float(np.clip(num / den, 0.0, 0.95)) if den > 0 else 0.0
    spread = 0.0
    if len(res) > 1:
        means = np.array([r.mean(axis=0) for r in res])  # (runs, sides)
        expect = np.mean([noise**2 * (1 + rho) / (1 - rho) / max(len(r), 1) for r in res])
        spread = float(math.sqrt(max(float(np.var(means, axis=0, ddof=1).mean()) - expect, 0.0)))
    return noise, spread, rho


def separating_drive(effects: tuple[str, str], models: dict[str, Any], like: InteractionLog, noise_a: float,
                     run_spread_a: float, autocorrelation: float, max_speed_mps: float,
                     max_omega_radps: float) -> SeparatingDrive | None:
    """Search :func:`manoeuvre_library` for the drive that separates the fitted ``models`` of ``effects``.

    Returns None when no manoeuvre makes the two predictions differ (they are the same model
    on every drive the library holds).
    """
    a, b = effects
    scored = []
    dt = 0.1
    kappa = (1 + autocorrelation) / (1 - autocorrelation)
    for name, text, profile in manoeuvre_library(max_speed_mps, max_omega_radps, dt):
        log = drive_log(profile, like)
        pa, pb = (np.asarray(models[n].predict(log), dtype=float) for n in (a, b))
        d = pb - pa
        ss = float(np.sum(d**2))
        if not ss > 0:
            continue
        # the noise is per logged sample: the drive, logged at the runs' rate, gives ``f`` samples per one here
        f = like.drive_rate_hz * dt
        var_t = kappa * noise_a**2 / (ss * f) + run_spread_a**2 * float(np.sum(d.sum(axis=0) ** 2)) / ss**2
        z = 1.0 / math.sqrt(var_t) if var_t > 0 else math.inf
        repeats = max(int(math.ceil((2 * REPEAT_Z / z) ** 2)), 1) if math.isfinite(z) else 1
        cand = DriveCandidate(name, text, float(profile.duration_s), float(math.sqrt(ss / d.size)), z, repeats)
        scored.append((cand, profile, {a: pa, b: pb}))
    if not scored:
        return None
    scored.sort(key=lambda c: (-c[0].z_per_repeat, c[0].duration_s))
    best, profile, preds = scored[0]
    return SeparatingDrive((a, b), best, profile, preds, float(noise_a), float(run_spread_a), float(autocorrelation),
                           tuple(c[0] for c in scored), {a: models[a], b: models[b]})
