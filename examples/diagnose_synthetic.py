"""Diagnose a physics model that lacks skid-steer turning resistance, on synthetic Husky logs.

The truth simulator (every physics effect on, realistic current noise) drives a Husky
through the vibration-current paper's excitation pattern — straights, arcs and pivots — on
coated wood, a few runs. The model under test is the physics current model with
turning resistance switched off, its idle current calibrated on a standstill log. The
diagnosis says where the gap lies, which catalogued effect explains it on held-out runs,
how far the gap shrinks, and returns the corrected model, which predicts like any other.

Run:  python examples/diagnose_synthetic.py [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from energy import PhysicsCurrentModel, TruthSimulator, excitation_commands, robot_preset
from energy.diagnosis import FitSettings, diagnose
from energy.sim import PAPER_GROUNDS

EFFECTS_WITHOUT_TURNING = ("inertia", "slope", "static_friction", "coulomb_friction", "stribeck",
                           "viscous_friction", "longitudinal_slip", "lateral_slip", "gear_losses",
                           "torque_saturation", "speed_saturation", "armature_heat")


def main(argv: list[str] | None = None) -> dict[str, float | str]:
    ap = argparse.ArgumentParser(description="Diagnose a physics model without turning resistance.")
    ap.add_argument("--quick", action="store_true", help="3 short runs instead of 5")
    ap.add_argument("--out", type=Path, default=None, help="write diagnosis.json and diagnosis.md here")
    args = ap.parse_args(argv)
    n_runs, duration_s = (3, 15.0) if args.quick else (5, 30.0)

    husky = robot_preset("husky")
    # every physics effect on: the truth (commands followed without lag, so the logged
    # commanded speeds are the speeds the robot drove)
    truth = TruthSimulator(husky, PAPER_GROUNDS, velocity_time_constant_s=0.0, seed=0)
    logs = []
    for k in range(n_runs):
        p = excitation_commands(duration_s, seed=k, omega_sign="both")
        logs.append(truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="coated_wood", seed=100 + k))

    # the model under test: no turning resistance; its rest level calibrated at standstill
    t = np.arange(500) * 0.01
    standstill = truth.simulate_commands(t, 0.0 * t, 0.0 * t, ground="coated_wood", seed=99)
    model = PhysicsCurrentModel(husky, PAPER_GROUNDS["coated_wood"], fit_parameters=("rest_current_a",),
                                effects=EFFECTS_WITHOUT_TURNING).fit([standstill])

    d = diagnose(model, logs, settings=FitSettings(seed=0, n_bootstrap=100))
    print("\n".join(d.verdict))
    best = d.current.ranking[0]
    print(f"\nbest explanation: {best.name} ({best.kind}), held-out shrink {best.shrink_pct:.1f} % "
          f"(95 % interval {best.shrink_interval_pct[0]:.1f} ... {best.shrink_interval_pct[1]:.1f} %)")
    for step in d.current.waterfall:
        print(f"  {step.label:<24} charge error {step.error_pct:+7.2f} %   RMSE {step.rmse:.3f} A")
    corrected = d.corrected_model.predict(logs[0])
    print(f"corrected model predicts {corrected.shape[0]} samples of run 0")
    if args.out is not None:
        written = d.write(args.out)  # diagnosis.json, diagnosis.md, the corrected model, the figures
        print(f"wrote {', '.join(p.name for p in written)} in {args.out}")
    return {"best": best.name, "shrink_pct": best.shrink_pct, "chosen": ",".join(d.current.chosen),
            "before_rmse_a": d.current.before.rmse, "after_rmse_a": d.current.after.rmse,
            "before_charge_error_pct": d.current.before.error_pct, "after_charge_error_pct": d.current.after.error_pct}


if __name__ == "__main__":
    main()
