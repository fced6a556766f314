"""``terrawatt diagnose``: where a current model's gap lies, which effect causes it, how far it shrinks (:func:`energy.diagnose`)."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import warnings
from pathlib import Path
from typing import Any

from energy import (
    GROUND_PRESETS,
    ROBOT_PRESETS,
    InteractionLog,
    PhysicsCurrentModel,
    diagnose,
    load_current_model,
    new_current_model,
)
from energy.diagnosis import DRIVE_EFFECTS, EFFECTS_CATALOGUE, FIGURES, plot_diagnosis
from terrain import FigureWarning, InvalidParameterError, UnknownNameError
from terrawatt_base.checks import check_seed, fmt_number
from terrawatt_base.dask_client import client_worker_count

from .common import (
    add_dask_options,
    add_map_options,
    check_dask_flags,
    check_outputs,
    dask_client_arg,
    input_paths,
    read_map_args,
)
from .data import add_data_options, logs_from_args

__all__ = ["add_parser", "run_diagnose"]

_OUTPUTS = ("diagnosis.json", "diagnosis.md", "corrected_model.zip", *FIGURES.values())


def add_parser(sub: Any) -> None:
    """The ``diagnose`` subcommand."""
    p = sub.add_parser(
        "diagnose",
        help="diagnose a current model's gap on logs: where it lies, which effect causes it, how far it shrinks",
    )
    p.add_argument("--model", required=True, metavar="physics|estimator|FILE",
                   help="'physics' (the robot and ground presets as given, or fitted on --calibration-data), "
                   "'estimator' (trained on --calibration-data) or a saved model file; never refitted on the "
                   "logs it diagnoses")
    p.add_argument("--robot", default=None, metavar="NAME",
                   help=f"robot preset of the physics ({', '.join(sorted(ROBOT_PRESETS))}; default husky)")
    p.add_argument("--ground", default=None, metavar="NAME",
                   help="--model physics: starting ground preset (default: the logs' ground when they share one "
                   "preset, else asphalt)")
    p.add_argument("--without", nargs="+", default=[], metavar="EFFECT",
                   help="--model physics: physics effects to switch off (diagnose a reduced model)")
    add_data_options(p)
    p.add_argument("--calibration-data", type=Path, default=None, metavar="DIR|FILE",
                   help="other runs (read like --data) to fit the physics model's coefficients on, or to train the "
                   "estimator on; they are not diagnosed and must not be among --data's")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder")
    p.add_argument("--effects", nargs="+", default=None, metavar="EFFECT",
                   help="candidate effects (default: the whole catalogue)")
    p.add_argument("--split", choices=["runs", "blocks"], default="runs",
                   help="held-out data: other runs (default) or contiguous blocks of each run")
    p.add_argument("--map", type=Path, default=None, metavar="FILE",
                   help="the map the logs drove on (slope effect, grade and map localisation, the map figure)")
    add_map_options(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (and of the estimator's training)")
    add_dask_options(p, "the candidate effects' scoring")
    p.add_argument("--quiet", action="store_true", help="no progress bars (estimator training, effect scoring)")
    p.set_defaults(run=run_diagnose)


def _check_effect_names(flag: str, names: list[str], allowed: tuple[str, ...], what: str) -> None:
    """Each of ``names`` once, and each one of ``allowed``; errors name the flag."""
    bad = [e for e in names if e not in allowed]
    if bad:
        raise UnknownNameError(f"{flag} {bad!r}: {what}; expected names from {list(allowed)!r}")
    if len(set(names)) != len(names):
        raise InvalidParameterError(f"{flag} names an effect twice: {names!r}")

def _check_flags(args: argparse.Namespace) -> None:
    """Names and numbers of the flags, before any work."""
    kind = args.model if args.model in ("physics", "estimator") else "file"
    if kind == "file" and not Path(args.model).is_file():
        raise InvalidParameterError(f"--model must be 'physics', 'estimator' or a model file; {args.model!r} is "
                                    "no file")
    if args.robot is not None and args.robot not in ROBOT_PRESETS:
        raise UnknownNameError(f"--robot {args.robot!r} is not a robot preset; known: {sorted(ROBOT_PRESETS)!r}")
    if args.map is None:
        given = [f for f, v in (("--landcover", args.landcover), ("--landcover-classes", args.landcover_classes),
                                ("--reproject", args.reproject), ("--cell-size", args.cell_size)) if v is not None]
        if given:
            raise InvalidParameterError(f"{', '.join(given)} describe(s) the map of --map MAP, which is not given")
    if kind != "physics":
        for flag, value in (("--ground", args.ground), ("--without", args.without)):
            if value:
                raise InvalidParameterError(f"{flag} applies to --model physics only, got --model {args.model!r}")
    if kind == "file" and args.calibration_data is not None:
        raise InvalidParameterError("--calibration-data applies to --model physics or estimator; a saved model is "
                                    "diagnosed as it is")
    if kind == "estimator" and args.calibration_data is None:
        raise InvalidParameterError("--model estimator needs --calibration-data DIR: the estimator has no preset, and "
                                    "training it on the logs it diagnoses would hide the gap (or give a saved model file)")
    if args.calibration_data is not None:
        if not args.calibration_data.exists():
            raise InvalidParameterError(f"--calibration-data {str(args.calibration_data)!r} does not exist")
        cal, data = args.calibration_data.resolve(), args.data.resolve()
        if cal == data or data in cal.parents or cal in data.parents:
            raise InvalidParameterError(f"--calibration-data {str(args.calibration_data)!r} overlaps --data "
                                        f"{str(args.data)!r}: calibrate on runs that are not diagnosed")
    if args.ground is not None and args.ground not in GROUND_PRESETS:
        raise UnknownNameError(f"--ground {args.ground!r} is not a ground preset; known: {sorted(GROUND_PRESETS)!r}")
    _check_effect_names("--without", args.without, DRIVE_EFFECTS, "not physics drive effects")
    if args.effects is not None:
        _check_effect_names("--effects", args.effects, EFFECTS_CATALOGUE, "not in the catalogue")
    try:
        check_seed(args.seed)
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"--seed: {exc}") from None
    check_dask_flags(args)


def _runs(logs: list[InteractionLog]) -> str:
    return f"{len(logs)} run{'s' if len(logs) != 1 else ''}"


def _calibration_logs(args: argparse.Namespace, logs: list[InteractionLog]) -> list[InteractionLog] | None:
    """The ``--calibration-data`` logs (none of them a diagnosed run), or None."""
    if args.calibration_data is None:
        return None
    cal = logs_from_args(args, require_currents=True, flag="--calibration-data")
    diagnosed = {log.meta.source for log in logs if log.meta.source}
    shared = sorted({log.meta.source for log in cal} & diagnosed)
    if shared:
        raise InvalidParameterError(f"--calibration-data holds runs that --data diagnoses too: {shared[:3]!r}; "
                                    "calibrate on runs that are not diagnosed")
    return cal


def _model(args: argparse.Namespace, logs: list[InteractionLog]) -> tuple[Any, str]:
    """The model under diagnosis and a sentence saying where it comes from.

    Never fitted on the logs it diagnoses: a preset as given, a model fitted or trained on
    ``--calibration-data``, or a saved file.
    """
    cal = _calibration_logs(args, logs)
    if args.model == "physics":
        grounds = {log.meta.ground_label for log in (cal or logs)}
        ground = args.ground or (grounds.pop() if len(grounds) == 1 and grounds <= set(GROUND_PRESETS) else "asphalt")
        robot = args.robot or "husky"
        effects = tuple(e for e in DRIVE_EFFECTS if e not in args.without)
        without = f" without {', '.join(args.without)}" if args.without else " (every drive effect)"
        if cal is None:
            model = PhysicsCurrentModel(robot, ground, fit_parameters=(),
                                        effects=None if not args.without else effects).fit(logs)
            return model, (f"model: physics, the {robot} and {ground} presets as given{without}, not fitted on the "
                           f"{_runs(logs)} it is diagnosed on (--calibration-data DIR fits its coefficients on other runs)")
        model = PhysicsCurrentModel(robot, ground, effects=None if not args.without else effects).fit(cal)
        fitted = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in model.fitted_.items())
        return model, (f"model: physics, {robot} starting from {ground}{without}; its coefficients fitted on the "
                       f"{_runs(cal)} of {args.calibration_data} ({fitted}), which are not diagnosed")
    if args.model == "estimator":
        model = new_current_model("estimator", seed=args.seed, progress=not args.quiet).fit(cal)
        return model, (f"model: the vibration estimator, trained on the {_runs(cal)} of {args.calibration_data}, "
                       "which are not diagnosed")
    model = load_current_model(args.model)
    return model, f"model: {type(model).__name__} loaded from {args.model}"


def _waterfall_table(diagnosis: Any) -> str:
    lines = [f"{'step':<28} {'charge err %':>12} {'8 s sect. %':>12} {'RMSE A':>8} {'shrink %':>9}"]
    for w in diagnosis.waterfall:
        lines.append(f"{w.label:<28} {w.charge_error_pct:>12.2f} {w.section_error_pct:>12.2f} {w.rmse_a:>8.3f} "
                     f"{w.shrink_pct:>9.1f}")
    return "\n".join(lines)


def _power_table(diagnosis: Any) -> str:
    lines = ["battery power (voltage x pack current):",
             f"{'step':<28} {'energy err %':>12} {'8 s sect. %':>12} {'RMSE W':>8} {'shrink %':>9}"]
    for w in diagnosis.power.waterfall:
        lines.append(f"{w.label:<28} {w.energy_error_pct:>12.2f} {w.section_error_pct:>12.2f} {w.rmse_w:>8.2f} "
                     f"{w.shrink_pct:>9.1f}")
    return "\n".join(lines)


def run_diagnose(args: argparse.Namespace) -> int:
    """``terrawatt diagnose``: diagnosis.json, diagnosis.md, corrected_model.zip and the figures.

    Flags and the output folder are checked before the logs are read; figures come last
    and a figure that fails is a warning on stderr, never a failed command.
    """
    _check_flags(args)
    check_outputs(args.out, _OUTPUTS, input_paths(args))
    terrain = read_map_args(args) if args.map is not None else None
    logs = logs_from_args(args, require_currents=True)
    model, origin = _model(args, logs)
    print(origin, flush=True)
    robot = args.robot if args.model != "physics" else None
    with dask_client_arg(args) as client:
        if client is not None:
            print(f"scoring effects on {client_worker_count(client)} dask workers", flush=True)
        diagnosis = diagnose(model, logs, terrain=terrain, effects=args.effects, split=args.split, seed=args.seed,
                             robot=robot, client=client, progress=not args.quiet)
    diagnosis = dataclasses.replace(diagnosis, model_note=origin.removeprefix("model: "))
    args.out.mkdir(parents=True, exist_ok=True)
    written = [diagnosis.write_json(args.out / "diagnosis.json"), diagnosis.write_markdown(args.out / "diagnosis.md"),
               diagnosis.corrected_model.save(args.out / "corrected_model.zip")]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FigureWarning)  # failures are printed below, once
        figures = plot_diagnosis(diagnosis, args.out, logs=logs, terrain=terrain, on_error="warn")
    print("\n".join(diagnosis.verdict))
    print()
    print(_waterfall_table(diagnosis))
    if diagnosis.power is not None:
        print()
        print(_power_table(diagnosis))
    for name, why in figures.skipped.items():
        print(f"skipped {FIGURES[name]}: {why}")
    for name, why in figures.failed.items():
        print(f"terrawatt: warning: could not draw {args.out / FIGURES[name]}: {why}", file=sys.stderr)
    written += list(figures.written.values())
    print(f"\n{len(logs)} runs; wrote {', '.join(str(p) for p in written)}")
    return 0
