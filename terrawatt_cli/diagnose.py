"""``terrawatt diagnose``: where a current model's gap lies, which effect causes it, how far it shrinks (:func:`energy.diagnose`)."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

from energy import ROBOT_PRESETS
from energy.diagnosis import (
    DIAGNOSIS_FILES,
    FitSettings,
    check_effect_names,
    check_model_source,
    diagnose,
    model_under_diagnosis,
)
from terrain import InvalidParameterError
from terrawatt_base.checks import check_seed
from terrawatt_base.dask_client import client_worker_count

from .common import (
    Checked,
    add_dask_options,
    add_map_options,
    check_dask_flags,
    check_outputs,
    compute_arg,
    flag_text,
    input_paths,
    map_arg,
    robot_arg,
    warn_figures,
)
from .data import add_data_options, logs_from_args

__all__ = ["add_parser", "run_diagnose"]

#: The flags of :func:`energy.diagnosis.model_under_diagnosis`' arguments (its errors name them).
_FLAGS = {"model": "--model", "ground": "--ground", "without": "--without", "calibration": "--calibration-data",
          "calibration_logs": "--calibration-data", "logs": "--data"}


def add_parser(sub: Any) -> None:
    """The ``diagnose`` subcommand."""
    p = sub.add_parser("diagnose", help="diagnose a current model's gap on logs: where it lies, which effect causes "
                       "it, how far it shrinks")
    p.add_argument("--model", required=True, metavar="physics|estimator|FILE",
                   help="'physics' (the robot and ground presets as given, or fitted on --calibration-data), "
                   "'estimator' (trained on --calibration-data) or a saved model file; never refitted on the "
                   "logs it diagnoses")
    p.add_argument("--robot", default=None, metavar="NAME|FILE.json", action=Checked, check=robot_arg,
                   help=f"robot of the physics: a preset ({', '.join(sorted(ROBOT_PRESETS))}; default husky) or a "
                   "robot file (energy.params.write_robot_file)")
    p.add_argument("--ground", default=None, metavar="NAME", help="--model physics: starting ground preset "
                   "(default: the logs' ground; each sample its own label's preset when they drive on several, as "
                   "a mission's logs; else asphalt). With --map, the physics as given drives the map's slope")
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
    p.add_argument("--map", type=Path, default=None, metavar="FILE|example",
                   help="the map the logs drove on (slope effect, grade and map localisation, the map figure); "
                   "'example': the bundled map (of terrawatt mission's logs)")
    add_map_options(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (and of the estimator's training)")
    add_dask_options(p, "the candidate effects' scoring")
    p.add_argument("--quiet", action="store_true", help="no progress bars (estimator training, effect scoring)")
    p.set_defaults(run=run_diagnose, flag_names=_FLAGS)


def _check_flags(args: argparse.Namespace) -> None:
    """The flags the library cannot check before any work: a map's flags without ``--map``, overlapping folders."""
    map_flags = {"--landcover": args.landcover, "--landcover-classes": args.landcover_classes,
                 "--reproject": args.reproject, "--cell-size": args.cell_size}
    given = [f for f, v in map_flags.items() if v is not None]
    if args.map is None and given:
        raise InvalidParameterError(f"{', '.join(given)} describe(s) the map of --map MAP, which is not given")
    check_model_source(args.model, calibration=args.calibration_data, robot=args.robot, ground=args.ground,
                       without=args.without)
    if (cal := args.calibration_data) is not None:
        if not cal.exists():
            raise InvalidParameterError(f"--calibration-data {str(cal)!r} does not exist")
        c, d = cal.resolve(), args.data.resolve()
        if c == d or d in c.parents or c in d.parents:
            raise InvalidParameterError(f"--calibration-data {str(cal)!r} overlaps --data {str(args.data)!r}: "
                                        "calibrate on runs that are not diagnosed")
    if args.effects is not None:
        check_effect_names(args.effects, "--effects")
    check_seed(args.seed, "--seed")
    check_dask_flags(args)


def run_diagnose(args: argparse.Namespace) -> int:
    """``terrawatt diagnose``: diagnosis.json, diagnosis.md, corrected_model.zip and the figures.

    Flags and the output folder are checked before the logs are read; a figure that fails is a
    warning on stderr, never a failed command.
    """
    _check_flags(args)
    check_outputs(args.out, DIAGNOSIS_FILES, input_paths(args))
    terrain = map_arg(args)[0] if args.map is not None else None
    logs = logs_from_args(args, require_currents=True)
    cal = None if args.calibration_data is None else logs_from_args(args, True, flag="--calibration-data")
    source = model_under_diagnosis(args.model, logs, calibration_logs=cal, calibration_label=str(args.calibration_data),
                                   robot=args.robot, ground=args.ground, without=args.without, seed=args.seed,
                                   progress=not args.quiet, terrain=terrain)
    source = dataclasses.replace(source, note=flag_text(source.note, "calibration_logs", _FLAGS))  # its flag, here
    print(f"model: {source.note}", flush=True)
    with compute_arg(args, progress=not args.quiet) as compute:
        if compute.client is not None:
            print(f"scoring effects on {client_worker_count(compute.client)} dask workers", flush=True)
        diagnosis = diagnose(source, logs, terrain=terrain, effects=args.effects,
                             settings=FitSettings(split=args.split, seed=args.seed), compute=compute)
    with warn_figures():
        written = diagnosis.write(args.out)
    print(diagnosis.summary())
    print(f"\n{len(logs)} runs; wrote {', '.join(str(p) for p in written)}")
    return 0
