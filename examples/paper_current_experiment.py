"""Synthetic reproduction of the vibration-current paper's experiment and its Table I.

The paper ("End-to-end current consumption estimation for a driving system of a mobile
robot considering geology") drives a robot about 160 s on each of three grounds — coated
wood, snow over stone tiles, snow over concrete — with a control pattern of stepped
(v, omega) combinations (v 0–0.4 m/s, omega 0–1.05 rad/s, its Fig. 5), twice per ground;
it trains the vibration-conditioned estimator on run 1, tests on run 2 and reports, per
drive side, the integrated current (mAh) measured and estimated over 8 sections and the
whole run with the error rate ``|estimate - truth| / truth`` (its Table I).

Here the robot is the Husky preset and the runs come from the library's truth simulator
(physics currents on the paper's grounds with patchy-snow variation, Husky-like current
noise and quantisation, ground-specific vibration). Both runs of a ground repeat the same
command pattern (the paper's setup) with different seeds for noise, ground variation and
vibration. The estimator is ``VibrationCurrentEstimator`` (``--model default`` or
``paper``); the linear baseline (I = a + b|v| + c|omega| + d dv/dt) is fitted on the same
run for comparison. The ground parameters and vibration signatures are estimates, not the
paper's robot: compare the layout and the orders of magnitude, not the digits.

Run: ``python examples/paper_current_experiment.py`` (about 15 s on 2 cores);
``--quick`` shortens the runs to 40 s and trains a tiny model (the test uses it).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from energy import (
    InteractionLog,
    LinearCurrentModel,
    NoiseModel,
    TruthSimulator,
    VibrationCurrentEstimator,
    charge_mah,
    estimator_preset,
    excitation_commands,
    plot_current_estimate,
    plot_vibration_spectra,
    robot_preset,
)
from energy.metrics import error_rate_pct, section_charges_mah
from energy.models import ESTIMATOR_PRESETS
from energy.sim import PAPER_GROUNDS, PAPER_VARIATION

#: Length of one run (s), as in the paper.
RUN_DURATION_S = 160.0
#: Length of a run with ``--quick`` (s).
QUICK_DURATION_S = 40.0
#: Sections per run in Table I.
N_SECTIONS = 8
#: Whole-run error rates (%) the paper reports on its robot, (right, left).
PAPER_WHOLE_RUN_ERROR_PCT = {
    "coated_wood": (3.15, 2.18),
    "snow_over_stone_tiles": (6.22, 15.4),
    "snow_over_concrete": (4.84, 15.47),
}
#: Current measurement of the synthetic runs (Husky-like: 0.13 A steps, 0.59 A idle).
NOISE = NoiseModel(current_noise_std_a=0.15, outlier_rate=0.002, outlier_magnitude_a=2.0,
                   quantisation_step_a=0.13, current_offset_a=0.59, side_gain_std=0.02,
                   accel_noise_std_mps2=0.02)


@dataclass(frozen=True)
class SideRow:
    """One cell group of Table I: truth and estimate (mAh) and the error rate (%)."""

    truth_mah: float
    estimate_mah: float
    error_pct: float


@dataclass(frozen=True)
class GroundTable:
    """Table I of one ground: 8 sections plus the whole run (last row), per side."""

    ground: str
    section_bounds_s: tuple[tuple[float, float], ...]
    right: tuple[SideRow, ...]
    left: tuple[SideRow, ...]
    baseline_error_pct: tuple[float, float]  # linear model, whole run (right, left)
    fit_duration_s: float


def simulate_runs(sim: TruthSimulator, ground: str, duration_s: float, seed: int) -> tuple[InteractionLog, InteractionLog]:
    """Runs 1 and 2 on one ground: the same command pattern, different measurement seeds."""
    pattern = excitation_commands(duration_s, 0.01, seed=seed)
    runs = tuple(
        sim.simulate_commands(pattern.time_s, pattern.v_mps, pattern.omega_radps, ground=ground,
                              seed=1000 * seed + 10 * k + i)
        for i, k in enumerate((1, 2))
    )
    return runs  # type: ignore[return-value]


def side_rows(time_s: np.ndarray, truth_a: np.ndarray, estimate_a: np.ndarray, section_s: float) -> tuple[SideRow, ...]:
    """Section rows and the whole-run row of one side."""
    _, q_true = section_charges_mah(time_s, truth_a, section_s)
    _, q_est = section_charges_mah(time_s, estimate_a, section_s)
    rows = [SideRow(float(a), float(b), float(error_rate_pct(b, a))) for a, b in zip(q_true, q_est)]
    whole_true, whole_est = charge_mah(time_s, truth_a), charge_mah(time_s, estimate_a)
    rows.append(SideRow(whole_true, whole_est, float(error_rate_pct(whole_est, whole_true))))
    return tuple(rows)


def make_model(name: str, quick: bool, seed: int) -> VibrationCurrentEstimator:
    """The estimator under test; ``quick`` shrinks it to a single tiny network."""
    config = estimator_preset(name)
    if quick:
        config = config.replace(n_members=1, max_epochs=10, hidden_sizes=(32,), patience=None, train_stride_s=0.05)
    return VibrationCurrentEstimator(config, seed=seed, n_threads=1)


def run_experiment(duration_s: float = RUN_DURATION_S, *, quick: bool = False, model: str = "default",
                   seed: int = 0, out_dir: Path | None = None) -> list[GroundTable]:
    """Simulate, train on run 1, test on run 2, for the three grounds of the paper.

    With ``out_dir``, also write the paper's Fig. 6 for each ground's test run
    (``current_<ground>.png``) and its Fig. 7 over all runs (``spectra.png``).
    """
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NOISE, variation=PAPER_VARIATION, seed=seed)
    section_s = duration_s / N_SECTIONS
    tables = []
    runs: list[InteractionLog] = []
    for ground in PAPER_GROUNDS:
        train, test = simulate_runs(sim, ground, duration_s, seed)
        runs += [train, test]
        t0 = time.perf_counter()
        estimator = make_model(model, quick, seed).fit(train)
        fit_s = time.perf_counter() - t0
        est = estimator.predict(test)
        if out_dir is not None:
            plot_current_estimate(test, est, out_dir / f"current_{ground}.png", label=f"{model} estimator",
                                  title=f"test run on {ground}: measured vs estimated current (the paper's Fig. 6)")
        base = LinearCurrentModel().fit(train).predict(test)
        t = test.time_s
        right = side_rows(t, test.current_right_a, est[:, 1], section_s)
        left = side_rows(t, test.current_left_a, est[:, 0], section_s)
        base_err = (
            float(error_rate_pct(charge_mah(t, base[:, 1]), right[-1].truth_mah)),
            float(error_rate_pct(charge_mah(t, base[:, 0]), left[-1].truth_mah)),
        )
        starts = t[0] + section_s * np.arange(len(right) - 1)
        bounds = tuple((float(a), float(min(a + section_s, t[-1]))) for a in starts)
        tables.append(GroundTable(ground, bounds, right, left, base_err, fit_s))
    if out_dir is not None:
        plot_vibration_spectra(runs, out_dir / "spectra.png", title="simulated vertical vibration by ground (Fig. 7)")
    return tables


def format_table(table: GroundTable) -> str:
    """Table I's layout for one ground."""
    head = (f"{'section':>7} {'time (s)':>13} | {'right truth':>11} {'estimate':>9} {'error %':>8} | "
            f"{'left truth':>10} {'estimate':>9} {'error %':>8}")
    unit = f"{'':>7} {'':>13} | {'(mAh)':>11} {'(mAh)':>9} {'':>8} | {'(mAh)':>10} {'(mAh)':>9} {'':>8}"
    lines = [f"Ground: {table.ground}  (fit {table.fit_duration_s:.1f} s)", head, unit, "-" * len(head)]
    labels = [str(k + 1) for k in range(len(table.section_bounds_s))] + ["whole"]
    spans = [f"{a:5.1f}-{b:5.1f}" for a, b in table.section_bounds_s]
    spans.append(f"{table.section_bounds_s[0][0]:5.1f}-{table.section_bounds_s[-1][1]:5.1f}")
    for label, span, r, lft in zip(labels, spans, table.right, table.left):
        if label == "whole":
            lines.append("-" * len(head))
        lines.append(f"{label:>7} {span:>13} | {r.truth_mah:11.3f} {r.estimate_mah:9.3f} {r.error_pct:8.2f} | "
                     f"{lft.truth_mah:10.3f} {lft.estimate_mah:9.3f} {lft.error_pct:8.2f}")
    return "\n".join(lines)


def format_summary(tables: Sequence[GroundTable], model: str) -> str:
    """Whole-run errors beside the linear baseline and the paper's numbers."""
    lines = [f"Whole-run error % (right / left): {model} estimator, linear baseline, paper (its robot)"]
    for tb in tables:
        pr, pl = PAPER_WHOLE_RUN_ERROR_PCT[tb.ground]
        lines.append(f"  {tb.ground:<22} {tb.right[-1].error_pct:6.2f} / {tb.left[-1].error_pct:6.2f}   "
                     f"{tb.baseline_error_pct[0]:6.2f} / {tb.baseline_error_pct[1]:6.2f}   {pr:6.2f} / {pl:6.2f}")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> list[GroundTable]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="40 s runs and a tiny model (for tests)")
    parser.add_argument("--model", default="default", choices=sorted(ESTIMATOR_PRESETS), help="estimator preset")
    parser.add_argument("--seed", type=int, default=0, help="seed of commands, noise and training")
    parser.add_argument("--out", type=Path, default=None, help="write the Fig. 6 / Fig. 7 figures into this directory")
    args = parser.parse_args(argv)
    duration = QUICK_DURATION_S if args.quick else RUN_DURATION_S
    t0 = time.perf_counter()
    tables = run_experiment(duration, quick=args.quick, model=args.model, seed=args.seed, out_dir=args.out)
    print(f"Synthetic Table I: Husky preset, {duration:g} s runs, train run 1 / test run 2, "
          f"model {args.model!r}{' (quick)' if args.quick else ''}\n")
    for tb in tables:
        print(format_table(tb) + "\n")
    print(format_summary(tables, args.model))
    print(f"\ntotal time {time.perf_counter() - t0:.1f} s")
    return tables


if __name__ == "__main__":
    main()
