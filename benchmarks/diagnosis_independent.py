"""Independent benchmark of ``terrawatt diagnose`` on logs of an independently written Husky simulator.

The project's own diagnosis benchmark draws its logs from the project's truth simulator, whose
functional forms are the catalogue's. Here the logs come from ``benchmarks/independent_sim.py``
(own skid-steer physics: Wong's radius-dependent turning resistance, a speed-squared
resistance, BorealTC-like measurement with a 0.59 A sensor offset, 0.13 A steps, ~6.5 Hz drive
and 100 Hz IMU streams), and the diagnosis is run as a user runs it: the ``terrawatt`` CLI on a
folder of CSV logs.

Protocol, for each case (one effect switched on in the diagnosed runs) and each seed:

- diagnosed runs: ``--runs`` runs (60-90 s each) with the case's effect, run seeds
  ``10000 + 1000 * seed + k``;
- calibration runs: as many runs of the unchanged robot (case ``none``), run seeds
  ``50000 + 1000 * seed + k`` — the robot before the change;
- bases, each diagnosed with ``terrawatt diagnose --data DIR --out OUT --quiet``:

  * ``preset``: ``--model physics --ground flooring``, the preset as the CLI gives it (whether
    the CLI refits it on the diagnosed runs is read from its first printed line and recorded);
  * ``calibrated``: ``PhysicsCurrentModel(sim.husky_robot(), "flooring").fit(calibration runs)``
    (the Husky preset with the simulator's drivetrain inertia: the preset holds the rotor alone, half
    of it, which the catalogue's ``rotor_inertia`` names on any run with hard starts), saved, then
    ``--model FILE``;
  * ``cal-turning`` / ``cal-viscous`` (for the cases whose nearest catalogue term is a physics
    term the full model already has, which the diagnosis then does not score, and for ``none``
    as their null and paired reference): the calibrated base without turning resistance /
    viscous friction, that term's coefficient left at the preset's value (not fitted on runs
    that cannot show it).

Scored per diagnosis: rank of the best-ranked hit effect, whether a hit was chosen first, the
hit's held-out shrink alone with its 95 % interval and its fitted parameters, the chosen effects,
the total held-out shrink and the whole-set charge error before -> after, the noise floor (the
RMSE between the logged currents and the same runs without noise, quantisation and per-run side
gains) and the shrink ceiling it allows ``100 (1 - noise^2 / RMSE_before^2)``, the attainable
shrink (the share of the gap the effect causes, from the ``none`` row of the same base and seed:
same manoeuvres and noise), the fitted value against the truth where one exists (mass scale,
left/right gain ratio, lag), and any plausibility flags the JSON carries. Summary rows: ranked first (target >= 80 %), median shrink
of the hit (target >= 60 %), null rate "nothing found and nothing added" on ``none`` (target
>= 95 %).

Usage::

    python benchmarks/diagnosis_independent.py --quick                    # 1 seed, ~1-3 min
    python benchmarks/diagnosis_independent.py --out out/diagnosis_independent.json   # 4 seeds
    python benchmarks/diagnosis_independent.py --cases payload payload:40 --seeds 2 --keep out/indep_runs
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import importlib.util
import inspect
import io
import json
import platform
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import energy
from energy.diagnosis import DRIVE_EFFECTS, EFFECTS_CATALOGUE
from terrawatt_base.atomic import write_json_atomic
from terrawatt_cli import main as terrawatt


def _sibling(name: str) -> Any:
    """Import ``benchmarks/<name>.py`` by path (benchmarks/ is no package)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, Path(__file__).resolve().parent / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while the class is built
    spec.loader.exec_module(module)
    return module


sim = _sibling("independent_sim")

DEFAULT_OUT = Path("out") / "diagnosis_independent.json"
#: Every case at its default size, and a second payload (40 kg: 1.8x the robot's mass).
DEFAULT_CASES = [*sim.CASES, "payload:40"]

#: Catalogue effects that count as a hit per case (the withheld effect or its nearest term).
HITS: dict[str, tuple[str, ...]] = {
    "none": (),
    # +80 kg: the catalogue's mass parameter scales every mass term, as the payload does
    "payload": ("mass",),
    # Wong's radius-dependent lateral coefficient: the catalogue's turning resistance, or, for a
    # base that has the term (fitted to ~0 on calibration runs without it), its coefficient re-sized
    "turning": ("turning_resistance", "lateral_friction"),
    # a gain on the left side's logged current
    "left_gain": ("current_gain",),
    # the drive stream's clock late against the IMU's: the catalogue's clock offset between the
    # IMU and the drive streams. It is a candidate only for models that read the IMU; the
    # physics bases here do not, and commands and currents move together, so for them the
    # shift is invisible and the right answer is "nothing" (see EXPECT_FOUND)
    "lag": ("imu_lag",),
    # currents late against the speeds: a lag of the whole prediction against the current
    "current_lag": ("time_lag",),
    # F = c v|v| per side: the catalogue's speed-squared drag, the same law (before it was catalogued the
    # nearest shapes, the linear viscous term and a rolling-resistance error, counted as hits: they no longer do)
    "speed_friction": ("quadratic_drag",),
}
#: Whether a correct diagnosis should find something on a calibrated physics base. On the
#: ``preset`` base ``none`` and ``lag`` are no null cases: the preset is not this robot (it has
#: turning resistance, this baseline robot has none), so they count in neither rate.
EXPECT_FOUND: dict[str, bool] = {case: bool(hits) for case, hits in HITS.items()} | {"lag": False}


def _truth(case: str) -> tuple[str, float] | None:
    """(how to read the size of the hit's fitted effect, the true size) where the case has one:
    the mass added (mass scale - 1, as a share of the robot's mass), the left gain's excess over
    the right's (gain_left / gain_right - 1), the lag (s), the speed-squared drag per side (N s^2/m^2)."""
    name = case.partition(":")[0]
    fx = sim.case_effects(case)
    return {
        "payload": ("mass_scale-1", fx.payload_kg / sim.MASS_KG),
        "left_gain": ("gain_left/gain_right-1", fx.left_gain - 1.0),
        "current_lag": ("lag_s", fx.current_lag_s),
        "speed_friction": ("drag_coef_n_s2_per_m2", fx.speed_friction_n_s2_per_m2),
    }.get(name)


def _hit_value(params: dict[str, float] | None, key: str) -> float | None:
    """The fitted size named by ``key`` ('p', 'p-1' or 'p/q-1'), None when a parameter is absent."""
    if not params:
        return None
    ratio, minus_one = key.removesuffix("-1"), key.endswith("-1")
    num, _, den = ratio.partition("/")
    if num not in params or (den and not params.get(den)):
        return None
    value = params[num] / params[den] if den else params[num]
    return value - 1.0 if minus_one else value


#: Reduced calibrated bases: the physics term left out and its coefficient (not fitted).
REDUCED: dict[str, tuple[str, str]] = {
    "cal-turning": ("turning_resistance", "lateral_friction_coef"),
    "cal-viscous": ("viscous_friction", "viscous_friction_coef_s_per_m"),
}
#: Cases diagnosed on each reduced base (``none``: its null and the paired reference).
REDUCED_CASES: dict[str, tuple[str, ...]] = {"cal-turning": ("turning", "none"), "cal-viscous": ("speed_friction", "none")}
BASES = ("preset", "calibrated", *REDUCED)
#: A checked fitted value is right within this relative error.
VALUE_TOL = 0.2  # of the effect's size
TARGETS = {"ranked_first_pct": 80.0, "median_hit_shrink_pct": 60.0, "null_pct": 95.0}

_unknown = sorted({e for hits in HITS.values() for e in hits} - set(EFFECTS_CATALOGUE))
if _unknown:
    raise SystemExit(f"hit effects {_unknown!r} are not in energy.diagnosis.EFFECTS_CATALOGUE {EFFECTS_CATALOGUE!r}")


def run_seed(seed: int, k: int, calibration: bool = False) -> int:
    """Seed of the k-th diagnosed (or calibration) run of a benchmark seed."""
    return (50_000 if calibration else 10_000) + 1000 * seed + k


# ------------------------------------------------------------------------------ running the CLI
def _cli(argv: list[str]) -> tuple[int, str, str]:
    """``terrawatt`` in-process: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = terrawatt(argv)
    return code, out.getvalue(), err.getvalue()


def _flags(d: dict[str, Any]) -> dict[str, Any]:
    """The plausibility flags the diagnosis JSON holds, read defensively: non-empty values of keys
    naming 'flag' at the top level and in each ranking entry ({effect name: flags})."""
    def pick(obj: dict[str, Any]) -> dict[str, Any]:
        return {k: v for k, v in obj.items() if "flag" in k.lower() and v not in (None, [], {}, "", False)}

    found = pick(d)
    for entry in d.get("ranking", []) or []:
        sub = pick(entry) if isinstance(entry, dict) else {}
        if sub:
            found.setdefault("ranking", {})[entry.get("name", "?")] = sub
    return found


def _score(d: dict[str, Any], case: str) -> dict[str, Any]:
    """The numbers of one diagnosis.json for a case."""
    hits = HITS[case]
    ranking = d.get("ranking", []) or []
    names = [r.get("name") for r in ranking]
    chosen = list(d.get("chosen", []) or [])
    kinds = {r.get("name"): r.get("kind") for r in ranking}
    ranks = {h: names.index(h) + 1 for h in hits if h in names}
    hit = min(ranks, key=ranks.get) if ranks else None
    entry = ranking[ranks[hit] - 1] if hit else None
    waterfall = d.get("waterfall", []) or []
    first = ranking[0] if ranking else None
    return {
        "hit": hit,
        "rank": ranks.get(hit) if hit else None,
        "hit_skipped": {h: d.get("skipped", {}).get(h) for h in hits if h not in names},
        "chosen": chosen,
        "chosen_first": bool(chosen) and chosen[0] in hits,
        "found": any(kinds.get(n) != "learned" for n in chosen),
        "nothing_added": not chosen,
        "hit_shrink_pct": entry.get("shrink_pct") if entry else None,
        "hit_shrink_interval_pct": entry.get("shrink_interval_pct") if entry else None,
        "hit_added_pct": entry.get("added_pct") if entry else None,
        "hit_parameters": entry.get("parameters") if entry else None,
        "first_ranked": None if first is None else {k: first.get(k) for k in ("name", "kind", "parameters", "shrink_pct",
                                                                            "shrink_interval_pct")},
        "top5": [(r.get("name"), r.get("added_pct"), r.get("shrink_pct")) for r in ranking[:5]],
        "total_shrink_pct": waterfall[-1].get("shrink_pct") if waterfall else None,
        "before": d.get("before", {}),
        "after": d.get("after", {}),
        "verdict": d.get("verdict", []),
        "flags": _flags(d),
        "chosen_flagged": [n for n in chosen if n in _flags(d).get("ranking", {})],
        # a tie named on the first chosen effect (diagnosis.json "indistinguishable")
        "tie_on_first": bool(chosen) and any(t.get("chosen") == chosen[0] for t in d.get("indistinguishable", []) or []),
        "hit_flagged": bool(hit and hit in _flags(d).get("ranking", {})),
    }


def _noise_rmse_a(logs: list[Any], ideal: list[Any]) -> float:
    """RMSE (A, both sides) between logged currents and the same runs without noise,
    quantisation and per-run side gains: what no model can explain."""
    diff = np.concatenate([np.column_stack([a.current_left_a - b.current_left_a, a.current_right_a - b.current_right_a])
                           for a, b in zip(logs, ideal)])
    return float(np.sqrt(np.mean(diff**2)))


def _calibrated(seed: int, runs: int, folder: Path, reduced: tuple[str, str] | None) -> tuple[Path, dict[str, float]]:
    """Fit (and save) the calibrated base of a seed on its calibration runs, or a reduced variant."""
    logs = [sim.simulate_run(run_seed(seed, k, calibration=True), sim.CASES["none"], label="none (calibration)")
            for k in range(runs)]
    if reduced is None:
        model = energy.PhysicsCurrentModel(sim.husky_robot(), "flooring")
        name = "calibrated.zip"
    else:
        term, coef = reduced
        default = inspect.signature(energy.PhysicsCurrentModel).parameters["fit_parameters"].default
        model = energy.PhysicsCurrentModel(
            sim.husky_robot(), "flooring", effects=tuple(e for e in DRIVE_EFFECTS if e != term),
            fit_parameters=tuple(p for p in default if p != coef),
        )
        name = f"calibrated_without_{term}.zip"
    model.fit(logs)
    path = model.save(folder / name)
    return path, dict(model.fitted_)


def run_case(case: str, seed: int, runs: int, work: Path, bases: tuple[str, ...],
             calibration_cache: dict[Any, tuple[Path, dict[str, float]]]) -> list[dict[str, Any]]:
    """Generate, write and diagnose one case for one seed; one row per base."""
    name = case.partition(":")[0]
    effects = sim.case_effects(case)
    folder = work / case.replace(":", "_") / f"seed{seed}"
    diagnosed = [sim.simulate_run(run_seed(seed, k), effects, label=case) for k in range(runs)]
    ideal = [sim.simulate_run(run_seed(seed, k), effects, ideal=True) for k in range(runs)]
    noise = _noise_rmse_a(diagnosed, ideal)
    sim.write_runs(diagnosed, folder / "data")
    rows = []
    for base in bases:
        if base in REDUCED and name not in REDUCED_CASES[base]:
            continue
        calibration: dict[str, float] | None = None
        if base == "preset":
            argv = ["--model", "physics", "--ground", "flooring"]
        else:
            key = (seed, REDUCED.get(base))
            if key not in calibration_cache:
                calibration_cache[key] = _calibrated(seed, runs, work / "calibration" / f"seed{seed}", key[1])
            path, calibration = calibration_cache[key]
            argv = ["--model", str(path)]
        out = folder / base
        t0 = time.perf_counter()
        code, stdout, stderr = _cli(["diagnose", *argv, "--data", str(folder / "data"), "--out", str(out), "--quiet"])
        row: dict[str, Any] = {
            "case": case, "base": base, "seed": seed, "hits": list(HITS[name]), "expect_found": EXPECT_FOUND[name],
            "expect_null": not EXPECT_FOUND[name] and base != "preset",
            "base_removed_term": REDUCED.get(base, (None,))[0],
            "runs": runs, "duration_s": float(sum(log.duration_s for log in diagnosed)),
            "noise_rmse_a": noise, "calibration_fitted": calibration, "exit_code": code,
            "cli_first_line": stdout.splitlines()[0] if stdout else "", "elapsed_s": time.perf_counter() - t0,
        }
        row["preset_refit"] = "fitted on the same" in row["cli_first_line"] if base == "preset" else None
        if code != 0:
            row["error"] = stderr.strip().splitlines()[-1] if stderr.strip() else f"exit code {code}"
        else:
            row.update(_score(json.loads((out / "diagnosis.json").read_text()), name))
            rmse = row["before"].get("rmse_a")
            row["noise_ceiling_pct"] = 100.0 * (1.0 - noise**2 / rmse**2) if rmse else None
            truth = _truth(case)
            value = _hit_value(row["hit_parameters"], truth[0]) if truth else None
            row["hit_value"] = None if truth is None else {"name": truth[0], "fitted": value, "truth": truth[1]}
            row["hit_value_ok"] = None if truth is None or value is None else abs(value / truth[1] - 1.0) <= VALUE_TOL
        rows.append(row)
    return rows


def add_attainable(rows: list[dict[str, Any]]) -> None:
    """Each row's attainable shrink: the share of its held-out squared gap that the case's effect
    causes, ``100 (1 - RMSE_none^2 / RMSE_case^2)`` with the ``none`` row of the same base and
    seed (the same manoeuvres and noise, without the effect). What an effect that explained the
    case's change exactly would shrink; None without a paired ``none`` row, and for the preset
    (whose gap on ``none`` is its own mismatch with this robot, not noise)."""
    none = {(r["base"], r["seed"]): r["before"].get("rmse_a") for r in rows
            if r["case"] == "none" and "error" not in r}
    for r in rows:
        ref = none.get((r["base"], r["seed"]))
        rmse = r.get("before", {}).get("rmse_a") if "error" not in r else None
        r["attainable_shrink_pct"] = (100.0 * (1.0 - ref**2 / rmse**2)
                                      if ref and rmse and r["case"] != "none" and r["base"] != "preset" else None)


# ------------------------------------------------------------------------------ printing
def _f(x: Any, fmt: str = ".1f") -> str:
    return "–" if x is None else format(x, fmt)


def _params(p: dict[str, float] | None) -> str:
    return "–" if not p else ", ".join(f"{k}={v:.3g}" for k, v in p.items())


def table(rows: list[dict[str, Any]]) -> str:
    """One line per diagnosis."""
    head = (f"{'case':<15} {'base':<11} {'seed':>4} {'rank':>4} {'1st':>3}  {'chosen':<40} {'hit shrink % [95 %]':<22} "
            f"{'total %':>7} {'attain %':>8} {'noise ceil %':>12}  {'charge err % before -> after':<28} fitted (hit)")
    lines = [head, "-" * len(head)]
    for r in rows:
        if "error" in r:
            lines.append(f"{r['case']:<15} {r['base']:<11} {r['seed']:>4}  error: {r['error']}")
            continue
        lo_hi = r["hit_shrink_interval_pct"]
        shrink = "–" if r["hit_shrink_pct"] is None else (
            f"{r['hit_shrink_pct']:.1f} [{lo_hi[0]:.1f}, {lo_hi[1]:.1f}]" if lo_hi else f"{r['hit_shrink_pct']:.1f}")
        chosen = ",".join(r["chosen"]) or "(nothing)"
        if len(chosen) > 40:
            chosen = chosen[:39] + "…"
        q = f"{_f(r['before'].get('charge_error_pct'))} -> {_f(r['after'].get('charge_error_pct'))}"
        check = r.get("hit_value")
        value = "" if not check or check["fitted"] is None else (
            f"  [{check['name']} {check['fitted']:.3g} vs {check['truth']:.3g}: {'ok' if r['hit_value_ok'] else 'off'}]")
        marks = [f"flagged: {','.join(r['chosen_flagged'])}"] if r["chosen_flagged"] else []
        if r["hit_flagged"] and r["hit"] not in r["chosen_flagged"]:
            marks.append(f"flagged: {r['hit']}")
        flag = "".join(f"  ({m})" for m in marks)
        lines.append(
            f"{r['case']:<15} {r['base']:<11} {r['seed']:>4} {_f(r['rank'], 'd'):>4} {'yes' if r['chosen_first'] else 'no':>3}  "
            f"{chosen:<40} {shrink:<22} {_f(r['total_shrink_pct']):>7} {_f(r['attainable_shrink_pct'], '.0f'):>8} "
            f"{_f(r['noise_ceiling_pct'], '.0f'):>12}  {q:<28} {_params(r['hit_parameters'])}{value}{flag}")
    return "\n".join(lines)


def _pct(k: int, n: int) -> float | None:
    return 100.0 * k / n if n else None


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def _stats(sel: list[dict[str, Any]]) -> dict[str, Any]:
    want = [r for r in sel if r["expect_found"]]
    null = [r for r in sel if r["expect_null"]]
    checked = [r for r in want if r["rank"] == 1 and r.get("hit_value_ok") is not None]
    return {
        "n_found_expected": len(want),
        "ranked_first_pct": _pct(sum(r["rank"] == 1 for r in want), len(want)),
        "chosen_first_pct": _pct(sum(r["chosen_first"] for r in want), len(want)),
        "ranked_first_value_ok": f"{sum(r['hit_value_ok'] for r in checked)}/{len(checked)}",
        # a hit that was not scored (skipped) or not ranked counts as 0
        "median_hit_shrink_pct": _median([r["hit_shrink_pct"] or 0.0 for r in want]),
        "median_attainable_shrink_pct": _median([r["attainable_shrink_pct"] for r in want
                                                 if r["attainable_shrink_pct"] is not None]),
        "median_total_shrink_pct": _median([r["total_shrink_pct"] or 0.0 for r in want]),
        # a clear winner (the hit chosen first) with no tie named on it (target >= 90 %)
        "clear_no_tie_pct": _pct(sum(not r.get("tie_on_first") for r in want if r["chosen_first"]),
                                 sum(r["chosen_first"] for r in want)),
        "n_null_expected": len(null),
        "null_pct": _pct(sum(r["nothing_added"] for r in null), len(null)),
        "null_catalogue_pct": _pct(sum(not r["found"] for r in null), len(null)),
    }


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Summary per base, over the calibrated bases, and per (case, base)."""
    ok = [r for r in rows if "error" not in r]
    bases = [b for b in BASES if any(r["base"] == b for r in ok)]
    cases = list(dict.fromkeys(r["case"] for r in ok))
    return {
        "by_base": {b: _stats([r for r in ok if r["base"] == b]) for b in bases},
        "calibrated_all": _stats([r for r in ok if r["base"] != "preset"]),
        "by_case": {f"{c} / {b}": _stats([r for r in ok if r["case"] == c and r["base"] == b])
                    for c in cases for b in bases if any(r["case"] == c and r["base"] == b for r in ok)},
        "n_errors": len(rows) - len(ok),
    }


def summary_table(summary: dict[str, Any]) -> str:
    """The summary rows and the targets."""
    head = (f"{'set':<30} {'n':>3} {'ranked 1st %':>12} {'chosen 1st %':>12} {'value ok':>8} {'med hit shrink %':>16} "
            f"{'med attain %':>12} {'med total %':>11} {'no tie %':>8} {'n null':>6} {'null %':>7} {'no catalogued %':>15}")
    lines = [head, "-" * len(head)]
    groups = [(f"base {b}", s) for b, s in summary["by_base"].items()]
    groups += [("calibrated, all variants", summary["calibrated_all"])]
    groups += list(summary["by_case"].items())
    for label, s in groups:
        lines.append(f"{label:<30} {s['n_found_expected']:>3} {_f(s['ranked_first_pct']):>12} "
                     f"{_f(s['chosen_first_pct']):>12} {s['ranked_first_value_ok']:>8} "
                     f"{_f(s['median_hit_shrink_pct']):>16} {_f(s['median_attainable_shrink_pct']):>12} "
                     f"{_f(s['median_total_shrink_pct']):>11} {_f(s['clear_no_tie_pct']):>8} "
                     f"{s['n_null_expected']:>6} {_f(s['null_pct']):>7} "
                     f"{_f(s['null_catalogue_pct']):>15}")
    lines.append(f"targets: ranked first >= {TARGETS['ranked_first_pct']:.0f} %, median hit shrink >= "
                 f"{TARGETS['median_hit_shrink_pct']:.0f} %, null ('nothing found and nothing added') >= "
                 f"{TARGETS['null_pct']:.0f} %. n: diagnoses where a hit is expected; n null: none and lag on the "
                 f"calibrated bases (the preset is not this robot); 'no catalogued': no catalogued effect chosen "
                 f"(a learned residual allowed); no tie: of the hits chosen first, those with no tie named on "
                 f"them (target >= 90 %); value ok: ranked-first hits whose fitted size is within "
                 f"{VALUE_TOL:.0%} of the truth (added mass, left/right gain excess, lag, drag)")
    return "\n".join(lines)


# ------------------------------------------------------------------------------ main
def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4, help="benchmark seeds per case (default 4)")
    ap.add_argument("--first-seed", type=int, default=0,
                    help="the first benchmark seed (default 0): seeds first-seed ... first-seed + seeds - 1")
    ap.add_argument("--runs", type=int, default=6, help="diagnosed runs (and calibration runs) per set (default 6)")
    ap.add_argument("--cases", nargs="+", default=DEFAULT_CASES, metavar="CASE[:VALUE]",
                    help=f"cases (default: {' '.join(DEFAULT_CASES)}); a value sets the effect's size, e.g. payload:40")
    ap.add_argument("--bases", nargs="+", default=list(BASES), choices=BASES, help="bases to diagnose (default all)")
    ap.add_argument("--quick", action="store_true", help="one seed (a smoke run of every case, ~1-3 min)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"JSON output (default {DEFAULT_OUT})")
    ap.add_argument("--keep", type=Path, default=None, metavar="DIR",
                    help="keep the generated logs, models and diagnosis folders here (default: a temporary folder)")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    if args.quick:
        args.seeds = 1
    if args.seeds < 1 or args.runs < 2 or args.first_seed < 0:
        ap.error(f"--seeds must be >= 1, --runs >= 2 and --first-seed >= 0, got {args.seeds}, {args.runs} and "
                 f"{args.first_seed}")
    for case in args.cases:
        try:
            sim.case_effects(case)
        except (KeyError, ValueError) as exc:
            ap.error(f"--cases: {exc}")
    work = args.keep if args.keep is not None else Path(tempfile.mkdtemp(prefix="diagnosis_independent_"))
    jobs = [(case, seed) for case in args.cases for seed in range(args.first_seed, args.first_seed + args.seeds)]
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover
        tqdm = None
    bar = tqdm(jobs, desc="diagnoses", unit="set", disable=args.no_progress) if tqdm else jobs
    rows: list[dict[str, Any]] = []
    cache: dict[Any, tuple[Path, dict[str, float]]] = {}
    t0 = time.perf_counter()
    try:
        for case, seed in bar:
            if tqdm:
                bar.set_postfix_str(f"{case} seed {seed}")
            rows += run_case(case, seed, args.runs, work, tuple(args.bases), cache)
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    elapsed = time.perf_counter() - t0
    add_attainable(rows)
    summary = summarise(rows)
    print(table(rows))
    print()
    print(summary_table(summary))
    first_lines = sorted({r["cli_first_line"] for r in rows if r["base"] == "preset"})
    refit = {r["preset_refit"] for r in rows if r["base"] == "preset"}
    if first_lines:
        print(f"\npreset base: the CLI {'refits' if refit == {True} else 'does not refit' if refit == {False} else 'mixed'} "
              f"the preset on the diagnosed runs; its first line (seed 0 of the first case):\n  {first_lines[0]}")
    flagged = sum(bool(r.get("chosen_flagged")) for r in rows)
    any_flags = sum(bool(r.get("flags")) for r in rows)
    print(f"plausibility flags: on a chosen effect in {flagged} of {len(rows)} diagnoses, anywhere in the ranking in "
          f"{any_flags} (0 everywhere: none, or the JSON has no such field)")
    print(f"{len(rows)} diagnoses in {elapsed:.0f} s")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(args.out, {
        "protocol": {
            "description": __doc__.split("Usage::")[0].strip(),
            "seeds": args.seeds, "first_seed": args.first_seed, "runs": args.runs, "cases": args.cases,
            "bases": args.bases,
            "hits": HITS, "expect_found": EXPECT_FOUND, "reduced": REDUCED, "reduced_cases": REDUCED_CASES,
            "targets": TARGETS, "value_tolerance": VALUE_TOL,
            "case_effects": {c: dataclasses.asdict(sim.case_effects(c)) for c in args.cases},
            "catalogue": list(EFFECTS_CATALOGUE),
        },
        "machine": {"python": platform.python_version(), "platform": platform.platform()},
        "elapsed_s": elapsed,
        "summary": summary,
        "rows": rows,
    })
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
