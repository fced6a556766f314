"""Few-shot update rules in seconds: the fitted folds' charges cached once, every rule scored on them.

``terrawatt evaluate --protocol few-shot`` adapts a model trained on the other grounds on the
first T s of one run of a held-out ground and scores each of the ground's other runs, whole
(total charge of both sides). A point update of the ``"regime"`` kind is linear in its
coefficients: the adapted charge of a scored run ``b`` on side ``k`` is its unadapted charge
plus ``coef_k @ integral(regime_basis(b, k) dt)``. So this benchmark fits each fold once,
caches per run the measured and unadapted charges and the integrals of the regime basis, and
per prefix the plain update's coefficients and its evidence (:func:`energy.models.adaptation.
evidence_parts`: the residual charge ``obs`` and the variances ``E`` noise, ``R`` run, ``G``
ground); a rule (a per-side factor, or new coefficients) then costs milliseconds. The clamp
at 0 of a log whose currents are all >= 0 is left out of the cached charges (its effect on the
plain update is printed: ``clamp``).

Folds: each ground held out in turn (outer), and inside each outer fold's training grounds
each ground held out in turn (inner: trained on the training grounds but one), so that a rule
with a free constant can choose it without the held-out ground.

Rules: the library's updates, and three candidates for an update that keeps the partition's fix where a prefix drove
one regime without its cost where it drove both (none with a free constant but (c)'s, chosen without the held-out
ground): (a) ``hierarchical``, the partition's levels sharing a common level learned in proportion to the prefix's
balance; (b) ``overlap``, the default applied to a run in proportion to the regime overlap of prefix and run; (c)
``switch``, the partition below a balance chosen on the other grounds (or, ``--choice-cache``, on another data set's).
And ``once``, the update shrunk once: read as the posterior mean of a run's offset under the learned spreads, the ridge
is the prior precision of a level, ``E T / (G + R)`` s (:func:`once_penalty`), and the ground's share ``G / (G + R)``
carries it to other runs — on the regime basis and on the partition; ``once, levels`` gives that penalty to the levels
only, the regime columns keeping the 20-s ridge.

Intervals: the cache (version 2) keeps what each scored run's forecast interval is made of (:func:`spread_parts`),
so the coverage of the default update's 50 / 80 / 95 % intervals per ground and T is scored with the base's spread
kept (the interval before it read the prefix), given the prefix (the library's) and, a candidate, its scale too
(:data:`INTERVAL_RULES`).

Printed (``--out``: JSON of every number): the coverage per ground, the diagnosis (per ground and T, which prefixes
the update harms most, on which side, and how the prefix's motion differs from the scored
runs'), then per ground and T the total-charge error median / p90 % of every rule against
the unadapted forecast and the gain baseline.

Usage::

    python benchmarks/adapt_rules.py --data borealtc --cache out/rules_boreal.pkl --out out/rules_boreal.json
    python benchmarks/adapt_rules.py --data generated --no-inner --cache out/rules_gen.pkl \
        --choice-cache out/rules_boreal.pkl --out out/rules_gen.json
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the generator beside this file

from energy import read_borealtc  # noqa: E402
from energy.evaluation import run_names, trim_to_overlap  # noqa: E402
from energy.logs import rest_samples  # noqa: E402
from energy.models import AdaptedCurrentModel, new_current_model  # noqa: E402
from energy.models.adaptation import evidence_parts, regime_basis  # noqa: E402
from energy.models.base import log_currents  # noqa: E402
from energy.models.uncertainty import sample_spans_s  # noqa: E402

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "borealtc"
CACHE_VERSION = 3  # 2: the scored runs' interval parts (``spread``); 3: the regime gains' basis (``xint_gain``)
TURN_SCALE_RADPS = 0.3  # the update's default
_trapezoid = getattr(np, "trapezoid", None) or np.trapz


def _stats(log: Any) -> dict[str, float]:
    """How a stretch was driven: mean |v| (m/s), mean turning share m, share of time at rest (|v| < 0.05 m/s)."""
    w = sample_spans_s(log)
    m = np.tanh(np.abs(log.omega_radps) / TURN_SCALE_RADPS)
    return {"v_mps": float(np.average(np.abs(log.v_mps), weights=w)), "turning": float(np.average(m, weights=w)),
            "rest": float(np.average(np.abs(log.v_mps) < 0.05, weights=w))}


def _basis(log: Any, k: int, moving: bool) -> np.ndarray:
    """The update's regime basis of side ``k``; with ``moving``, zero at rest (as the interval's regime design)."""
    x = regime_basis(log, k, TURN_SCALE_RADPS)
    return x * (~rest_samples(log))[:, None] if moving else x


def basis_integrals(log: Any, moving: bool = False) -> np.ndarray:
    """``integral(basis(log, k) dt)`` per side, shape (2, 4) (A s per unit coefficient)."""
    return np.stack([_trapezoid(_basis(log, k, moving), log.time_s, axis=0) for k in range(2)])


def normal_equations(log: Any, residual: np.ndarray, moving: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per side the update's time-weighted ``X'WX`` (2, 4, 4) and ``X'Wr`` (2, 4) (the ridge adds ``prior_s``)."""
    w = sample_spans_s(log)
    xs = [_basis(log, k, moving) for k in range(2)]
    return (np.stack([(x * w[:, None]).T @ x for x in xs]),
            np.stack([(x * w[:, None]).T @ residual[:, k] for k, x in enumerate(xs)]))


def gain_basis(log: Any, pred: np.ndarray, k: int) -> np.ndarray:
    """The ``"regime_gain"`` update's basis of side ``k``: ``[(1 - m) * predicted, m * predicted]``."""
    m = np.tanh(np.abs(log.omega_radps) / TURN_SCALE_RADPS)
    return np.column_stack([(1.0 - m) * pred[:, k], m * pred[:, k]])


def gain_integrals(log: Any, pred: np.ndarray) -> np.ndarray:
    """``integral(gain_basis(log, pred, k) dt)`` per side, shape (2, 2)."""
    return np.stack([_trapezoid(gain_basis(log, pred, k), log.time_s, axis=0) for k in range(2)])


def gain_normal_equations(log: Any, pred: np.ndarray, residual: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per side ``X'WX`` (2, 2, 2), ``X'Wr`` (2, 2) of the regime gains and each column's mean ``|x|`` (2, 2) (the
    ridge's scale, as the library's)."""
    w = sample_spans_s(log)
    xs = [gain_basis(log, pred, k) for k in range(2)]
    return (np.stack([(x * w[:, None]).T @ x for x in xs]),
            np.stack([(x * w[:, None]).T @ residual[:, k] for k, x in enumerate(xs)]),
            np.stack([np.average(np.abs(x), axis=0, weights=w) for x in xs]))


def fold_cache(model: Any, runs: list, names: list[str], adapt_seconds: tuple[float, ...]) -> dict[str, Any]:
    """Everything a rule needs of one few-shot fold (``model`` fitted without ``runs``' ground)."""
    base = [model.predict(r) for r in runs]
    out: dict[str, Any] = {"runs": [], "prefixes": [], "pairs": {}}
    for r, name, p in zip(runs, names, base):
        y = log_currents(r)
        out["runs"].append({"name": name, "q_true": _trapezoid(y, r.time_s, axis=0),
                            "q_base": _trapezoid(p, r.time_s, axis=0), "xint": basis_integrals(r),
                            "xint_moving": basis_integrals(r, moving=True), "xint_gain": gain_integrals(r, p),
                            "duration_s": r.duration_s,
                            "stats": _stats(r), "spread": spread_parts(model, r, p)})
    for a, run_a in enumerate(runs):
        t = run_a.time_s
        for T in adapt_seconds:
            if run_a.duration_s < T:
                continue
            prefix = run_a.slice(float(t[0]), float(t[0] + T))
            upd = AdaptedCurrentModel(model, method="regime", shrink="none", scope="ground").fit(prefix)
            pp = model.predict(prefix)
            yy = log_currents(prefix)
            obs, noise, run_v, ground_v = evidence_parts(model, [prefix], [pp], [yy])
            q_pred = _trapezoid(pp, prefix.time_s, axis=0)
            q_true = _trapezoid(yy, prefix.time_s, axis=0)
            gain = np.where(q_pred > 0, q_true / np.where(q_pred > 0, q_pred, 1.0), 1.0)
            out["prefixes"].append({"a": a, "T": float(T), "coef": upd.coefficients_.copy(), "obs": obs, "E": noise,
                                    "R": run_v, "G": ground_v, "gain": gain, "xint": basis_integrals(prefix),
                                    "stats": _stats(prefix), "nonneg": upd.nonnegative_,
                                    "normal": normal_equations(prefix, yy - pp, False),
                                    "normal_moving": normal_equations(prefix, yy - pp, True),
                                    "normal_gain": gain_normal_equations(prefix, pp, yy - pp)})
            for b, run_b in enumerate(runs):  # the exact (clamped) plain update, to size the clamp left out
                if b != a:
                    out["pairs"][(a, float(T), b)] = _trapezoid(upd.correct(run_b, base[b]), run_b.time_s, axis=0)
    return out


def spread_parts(model: Any, log: Any, pred: np.ndarray) -> dict[str, Any]:
    """What a scored run's forecast interval is made of, per sample and side (A²): the run spread of a known ground
    (``own2``), the new-ground part (``ground2``, zero on a known ground) and the members' disagreement (``ens2``);
    per side the per-sample noise's charge variance (``white2``, A² s²), and the predictive's ``dof``.

    ``run_sd² = own2 + ground2 + ens2`` is the base forecast's run spread exactly, so an interval rule can rescale
    the new-ground part and integrate (:func:`total_sd`)."""
    f = model.predict_distribution(log)
    interval = model.interval_
    own2 = interval.run_sd_a(log, pred, known=True) ** 2
    known = model.knows_ground(log.meta.ground_label)
    ground2 = (np.zeros_like(own2) if known or interval.new_ground_cov is None
               else interval.run_sd_a(log, pred, known=True, cov=interval.new_ground_cov) ** 2)
    ens2 = np.maximum(f.run_sd_a ** 2 - own2 - ground2, 0.0)
    dt = np.gradient(log.time_s)
    return {"t": log.time_s.copy(), "own2": own2, "ground2": ground2, "ens2": ens2,
            "white2": np.sum((f.sample_sd_a * dt[:, None]) ** 2, axis=0), "dof": float(f.dof),
            "total_sd": f.charge().total_sd_as}


def total_sd(sp: dict[str, Any], ground_factor: np.ndarray | float = 1.0, scale2: float = 1.0,
             own_factor: np.ndarray | float = 1.0) -> float:
    """The total charge's scale of a scored run with the new-ground part of its run spread times ``ground_factor``
    and a run's own part times ``own_factor`` (per side), and every part times ``scale2`` (as
    :meth:`CurrentForecast.charge`)."""
    gf = np.broadcast_to(np.asarray(ground_factor, dtype=np.float64), (2,))
    of = np.broadcast_to(np.asarray(own_factor, dtype=np.float64), (2,))
    run = np.sqrt(scale2 * (of[None, :] * sp["own2"] + gf[None, :] * sp["ground2"] + sp["ens2"]))
    q_run = _trapezoid(run, sp["t"], axis=0)
    return float(np.sqrt(float(q_run.sum()) ** 2 + scale2 * float(np.sum(sp["white2"]))))


# ------------------------------------------------------------- intervals
#: The central levels whose coverage the interval rules are scored on.
LEVELS = (0.5, 0.8, 0.95)


IntervalRule = Callable[[dict[str, Any], np.ndarray, dict[str, Any]], tuple[np.ndarray, np.ndarray, float]]


def interval_kept(p: dict[str, Any], coef: np.ndarray, rb: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float]:
    """The interval before it read the prefix: the base forecast's spread, whatever the update."""
    return np.ones(2), np.ones(2), rb["spread"]["dof"]


def interval_given_prefix(p: dict[str, Any], coef: np.ndarray, rb: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float]:
    """The library's (``AdaptedCurrentModel.correct_distribution``): the new-ground part scaled by the posterior
    variance of the ground's offset given the prefix's ``obs`` plus the update's departure from that posterior's mean
    (standardised), per side; the next run's own spread and the dof kept. Without the clamp at 0 (as every cached
    charge)."""
    return _given_prefix(p, coef, rb, np.ones(2)), np.ones(2), rb["spread"]["dof"]


def interval_given_scale(p: dict[str, Any], coef: np.ndarray, rb: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float]:
    """A candidate, measured and dropped (docs/results.md): as :func:`interval_given_prefix` with the learned spreads'
    scale updated by the prefix, the conjugate update of a normal's unknown variance by one look — the posterior and
    the next run's own spread times ``kappa = (nu + z²) / (nu + 1)`` (``z² = obs² / (G + R + E)``), ``nu + 1``
    degrees of freedom. Without the clamp at 0 (as every cached charge)."""
    nu = rb["spread"]["dof"]
    total = p["G"] + p["R"] + p["E"]
    if not np.isfinite(nu) or not np.any(p["G"] > 0):
        return interval_given_prefix(p, coef, rb)
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = np.where(total > 0, (nu + p["obs"] ** 2 / total) / (nu + 1.0), 1.0)
    return _given_prefix(p, coef, rb, kappa), kappa, nu + 1.0


def _given_prefix(p: dict[str, Any], coef: np.ndarray, rb: dict[str, Any], kappa: np.ndarray) -> np.ndarray:
    """Per side, the factor of the new-ground part given the prefix (its posterior times ``kappa``, plus the
    update's departure from the posterior mean, standardised)."""
    G, R, E, obs = p["G"], p["R"], p["E"], p["obs"]
    sp = rb["spread"]
    v_sd = _trapezoid(np.sqrt(sp["ground2"]), sp["t"], axis=0)
    d = np.sum(coef * rb["xint"], axis=1)
    total = G + R + E
    with np.errstate(divide="ignore", invalid="ignore"):
        post = np.where(total > 0, (R + E) / total, 1.0)
        bias = np.where((G > 0) & (v_sd > 0), G / total * obs / np.sqrt(G) - d / v_sd, 0.0)
    return np.where(G > 0, kappa * post + bias**2, 1.0)


INTERVAL_RULES: dict[str, IntervalRule] = {"kept": interval_kept, "given the prefix": interval_given_prefix,
                                           "its scale too": interval_given_scale}


def interval_rows(fold: dict[str, Any], rule: Rule, factor: IntervalRule) -> list[dict[str, Any]]:
    """Per (prefix, scored run): the standardised total-charge error of the update ``rule`` with the interval rule
    ``factor``, and the central level its predictive needs to hold the measurement."""
    from energy.models.forecast import central_level

    out = []
    for p in fold["prefixes"]:
        coef, key = _resolve(rule(p, fold))
        if key != "xint":
            raise ValueError("the interval rules take updates on the whole-run basis")
        for b, rb in enumerate(fold["runs"]):
            if b == p["a"]:
                continue
            c = _at(coef, rb)
            q_true = float(np.sum(rb["q_true"]))
            ground_f, own_f, dof = factor(p, c, rb)
            sd = total_sd(rb["spread"], ground_f, own_factor=own_f)
            z = (q_true - float(np.sum(rb["q_base"] + np.sum(c * rb["xint"], axis=1)))) / sd
            out.append({"T": p["T"], "z": z, "level": float(central_level(z, dof)),
                        "log_score": log_score(z, dof, sd / q_true)})
    return out


def log_score(z: float, dof: float, rel_sd: float) -> float:
    """The log predictive density of the measured charge relative to itself (a proper score: higher is better):
    the standardised error's density under the forecast's Student-t (Gaussian for ``dof = inf``), over the scale."""
    from scipy.stats import norm
    from scipy.stats import t as student_t

    dens = float(norm.logpdf(z)) if np.isinf(dof) else float(student_t.logpdf(z, dof))
    return dens - float(np.log(rel_sd))


def coverage(rows: list[dict[str, Any]]) -> list[float]:
    """Coverage % of the :data:`LEVELS` intervals, then the median |z| and the mean log score (:func:`log_score`)."""
    lv = np.array([r["level"] for r in rows])
    return [100.0 * float(np.mean(lv <= L)) for L in LEVELS] + [float(np.median(np.abs([r["z"] for r in rows]))),
                                                               float(np.mean([r["log_score"] for r in rows]))]


def interval_table(cache: dict[str, Any], rule: Rule, Ts: tuple[float, ...]) -> dict[str, Any]:
    """Per ground (then pooled), T and interval rule: coverage of the update ``rule``'s forecasts; ``unadapted`` the
    base forecast of every run (its interval unchanged by any rule)."""
    out: dict[str, Any] = {}
    pooled: dict[str, list[dict[str, Any]]] = {}
    for g, fold in list(cache["outer"].items()) + [("all", None)]:
        out[g] = {}
        if fold is None:
            out[g] = {name: {f"{T:g}": coverage([r for r in rows if r["T"] == T]) for T in Ts}
                      for name, rows in pooled.items() if name != "unadapted"}
            out[g]["unadapted"] = coverage(pooled["unadapted"])
            continue
        from energy.models.forecast import central_level

        base = []
        for rb in fold["runs"]:
            q_true = float(np.sum(rb["q_true"]))
            z = (q_true - float(np.sum(rb["q_base"]))) / rb["spread"]["total_sd"]
            base.append({"T": 0.0, "z": z, "level": float(central_level(z, rb["spread"]["dof"])),
                         "log_score": log_score(z, rb["spread"]["dof"], rb["spread"]["total_sd"] / q_true)})
        pooled.setdefault("unadapted", []).extend(base)
        out[g]["unadapted"] = coverage(base)
        for name, factor in INTERVAL_RULES.items():
            rows = interval_rows(fold, rule, factor)
            pooled.setdefault(name, []).extend(rows)
            out[g][name] = {f"{T:g}": coverage([r for r in rows if r["T"] == T]) for T in Ts}
    return out


def load_logs(kind: str, data: Path, seed: int) -> list:
    """The shared BorealTC logs, or the independent generator's grounds (``forecast_grounds.py``, 6 x 4 runs)."""
    if kind == "borealtc":
        return [trim_to_overlap(lg) for lg in read_borealtc(data)]
    from forecast_grounds import draw_grounds, ground_logs

    return [trim_to_overlap(lg) for lg in ground_logs(draw_grounds(6, seed), 4, seed)]


def build_cache(logs: list, seed: int, adapt_seconds: tuple[float, ...], inner: bool,
                cache: dict[str, Any] | None = None, save: Callable[[dict[str, Any]], None] | None = None) -> dict[str, Any]:
    """Outer folds (each ground held out) and, with ``inner``, the inner folds of each outer training set.

    ``cache``: a partial one to complete (the grounds it holds are kept); ``save`` is called after each outer fold,
    so a long build stopped half-way resumes where it stopped.
    """
    names = run_names(logs)
    grounds = list(dict.fromkeys(str(lg.meta.ground_label) for lg in logs))
    models: dict[frozenset, Any] = {}

    def fold(train: frozenset, target: str) -> dict[str, Any]:
        if train not in models:
            t0 = time.perf_counter()
            models[train] = new_current_model("estimator", seed=seed).fit(
                [lg for lg in logs if str(lg.meta.ground_label) in train])
            print(f"  fitted on {sorted(train)} in {time.perf_counter() - t0:.0f} s", flush=True)
        idx = [i for i, lg in enumerate(logs) if str(lg.meta.ground_label) == target]
        return fold_cache(models[train], [logs[i] for i in idx], [names[i] for i in idx], adapt_seconds)

    if cache is None:
        cache = {"version": CACHE_VERSION, "grounds": grounds, "outer": {}, "inner": {}, "complete": False}
    for g in grounds:
        if g in cache["outer"]:
            continue
        train = frozenset(grounds) - {g}
        cache["outer"][g] = fold(train, g)
        if inner and len(train) >= 2:
            cache["inner"][g] = {h: fold(train - {h}, h) for h in sorted(train)}
        cache["complete"] = len(cache["outer"]) == len(grounds)
        if save is not None:
            save(cache)
    return cache


# ------------------------------------------------------------------ rules
# A rule maps (prefix entry, fold) to the coefficients (2, 4) added on the scored runs; or to a function of the scored
# run's entry giving them (a rule that depends on the run it forecasts); or to (either, "xint_moving").
Rule = Callable[[dict[str, Any], dict[str, Any]], Any]


def _resolve(out: Any) -> tuple[Any, str]:
    """A rule's output as (coefficients or a function of the scored run, the key of the run's basis integrals)."""
    return out if isinstance(out, tuple) else (out, "xint")


def _at(coef: Any, rb: dict[str, Any]) -> np.ndarray:
    return coef(rb) if callable(coef) else coef


def _scaled(lam: np.ndarray, p: dict[str, Any]) -> np.ndarray:
    return p["coef"] * np.clip(np.nan_to_num(lam, nan=0.0), 0.0, 1.0)[:, None]


def rule_none(p: dict, f: dict) -> np.ndarray:
    return p["coef"]


def rule_unadapted(p: dict, f: dict) -> np.ndarray:
    return np.zeros_like(p["coef"])


def rule_prior(p: dict, f: dict) -> np.ndarray:
    """The default: ``G / (G + R + E)``; without a learned ground spread the evidence shrink."""
    if not np.any(p["G"] > 0):
        return rule_evidence(p, f)
    return _scaled(p["G"] / (p["G"] + p["R"] + p["E"]), p)


def rule_evidence(p: dict, f: dict) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return _scaled(np.where(p["obs"] ** 2 > 0, 1.0 - (p["E"] + p["R"]) / p["obs"] ** 2, 0.0), p)


def ridge(p: dict[str, Any], prior_s: float = 20.0, moving: bool = False) -> np.ndarray:
    """The plain update's coefficients (2, 4) refitted with penalty ``prior_s`` (s), on the basis zero at rest or not."""
    xtx, xtr = p["normal_moving" if moving else "normal"]
    return np.stack([np.linalg.solve(xtx[k] + prior_s * np.eye(4), xtr[k]) for k in range(2)])


def _prior_factor(p: dict[str, Any]) -> np.ndarray:
    total = p["G"] + p["R"] + p["E"]
    return np.divide(p["G"], total, out=np.zeros(2), where=total > 0)


def rule_prior_moving(p: dict, f: dict) -> tuple[np.ndarray, str]:
    """The default's factor on an update whose basis is zero at rest (fitted and applied on driving only)."""
    if not np.any(p["G"] > 0):
        return rule_evidence(p, f), "xint"
    return ridge(p, moving=True) * _prior_factor(p)[:, None], "xint_moving"


#: From the update's basis ``[1, |v|, m, m outer]`` to the partition ``[1 - m, |v|, m, m outer]``: straight driving and
#: turning get one level each, so a prefix that only pivots (m = 1) leaves the straight level at its prior, zero.
PARTITION = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [-1, 0, 1, 0], [0, 0, 0, 1]])


def partition_coef(p: dict[str, Any], prior_s: float = 20.0, moving: bool = False) -> np.ndarray:
    """The update refitted on the regime partition (same ridge), returned as coefficients of the update's basis."""
    xtx, xtr = p["normal_moving" if moving else "normal"]
    m = PARTITION
    return np.stack([m @ np.linalg.solve(m.T @ xtx[k] @ m + prior_s * np.eye(4), m.T @ xtr[k]) for k in range(2)])


def rule_partition(p: dict, f: dict) -> np.ndarray:
    """The plain update on the regime partition: a regime the prefix did not drive keeps no correction."""
    return partition_coef(p)


def rule_partition_prior(p: dict, f: dict) -> np.ndarray:
    """The regime partition shrunk by the default's factor."""
    return partition_coef(p) * _prior_or_evidence_factor(p, f)[:, None]


def regime_gain_coef(p: dict[str, Any], prior_s: float = 20.0) -> np.ndarray:
    """The ``"regime_gain"`` update's coefficients (2, 2): ``[straight gain - 1, turning gain - 1]`` per side, the ridge
    ``prior_s`` seconds on each column's own current scale (``max(mean |x|, 0.5)²``, as the library's)."""
    xtx, xtr, avg = p["normal_gain"]
    return np.stack([np.linalg.solve(xtx[k] + np.diag(prior_s * np.maximum(avg[k], 0.5) ** 2), xtr[k])
                     for k in range(2)])


def rule_regime_gain(p: dict, f: dict) -> tuple[np.ndarray, str]:
    """The regime gains, unshrunk."""
    return regime_gain_coef(p), "xint_gain"


def rule_regime_gain_prior(p: dict, f: dict) -> tuple[np.ndarray, str]:
    """The regime gains shrunk by the default's factor (the library's ``method="regime_gain"``)."""
    return regime_gain_coef(p) * _prior_or_evidence_factor(p, f)[:, None], "xint_gain"


def rule_partition_moving_prior(p: dict, f: dict) -> tuple[np.ndarray, str]:
    """The regime partition on driving only (no correction at rest), shrunk by the default's factor."""
    lam = _prior_factor(p) if np.any(p["G"] > 0) else np.ones(2)
    return partition_coef(p, moving=True) * lam[:, None], "xint_moving"


def regime_seconds(xint: np.ndarray) -> np.ndarray:
    """Soft seconds of a stretch straight (rest included) and turning, ``[integral(1 - m) dt, integral(m dt)]``, from its
    basis integrals (``m`` is the same on both sides)."""
    return np.array([xint[0, 0] - xint[0, 2], xint[0, 2]])


def balance(xint: np.ndarray) -> float:
    """``2 min(straight s, turning s) / T``: 0 when a stretch drove one regime only, 1 when half and half."""
    s = regime_seconds(xint)
    return float(2.0 * s.min() / max(s.sum(), 1e-12))


#: From the update's basis ``[1, |v|, m, m outer]`` to a common level plus one deviation per regime, ``[1, 1 - m, m,
#: |v|, m outer]`` (the columns of the first two rows of the partition, and a level shared by both).
HIERARCHY = np.array([[1.0, 1, 0, 0, 0], [0, 0, 0, 1, 0], [0, -1, 1, 0, 0], [0, 0, 0, 0, 1]])


def hierarchical_coef(p: dict[str, Any], prior_s: float = 20.0) -> np.ndarray:
    """Candidate (a): the partition's levels sharing a common level whose ridge is ``prior_s / balance``.

    Each regime's level is the common level plus its own deviation (ridge ``prior_s`` each, as every column of the
    update). A prefix that drove one regime only (balance 0) cannot tell the common level from that regime's
    deviation, so it learns none: the partition, other regimes left at zero. The more evenly it drove both, the more
    the common level learns from all its seconds, down to the same ridge as the deviations at half and half.
    """
    beta = balance(p["xint"])
    xtx, xtr = p["normal"]
    if beta > 1e-9:
        m, pen = HIERARCHY, np.array([prior_s / beta] + [prior_s] * 4)
    else:
        m, pen = HIERARCHY[:, 1:], np.full(4, prior_s)
    return np.stack([m @ np.linalg.solve(m.T @ xtx[k] @ m + np.diag(pen), m.T @ xtr[k]) for k in range(2)])


def _prior_or_evidence_factor(p: dict[str, Any], f: dict[str, Any]) -> np.ndarray:
    """The default's factor; without a learned ground spread, the evidence shrink's factor (as the library)."""
    if np.any(p["G"] > 0):
        return _prior_factor(p)
    lam = rule_evidence(p, f)[:, 0] / np.where(p["coef"][:, 0] != 0, p["coef"][:, 0], 1.0)
    return np.clip(lam, 0.0, 1.0)


def rule_hierarchical_prior(p: dict, f: dict) -> np.ndarray:
    """Candidate (a), shrunk by the default's factor."""
    return hierarchical_coef(p) * _prior_or_evidence_factor(p, f)[:, None]


def once_penalty(p: dict[str, Any]) -> np.ndarray:
    """Per side, the ridge penalty (s) that makes the update the posterior mean of a run's whole offset: ``E T / (G + R)``.

    The residual is white noise of density ``E / T`` (A² s: ``E`` is its charge's variance over the prefix's ``T``
    seconds) around ``x (g + u)``, a ground offset ``g`` and the run's own ``u``, whose level's prior variance is
    ``(G + R) / T²`` (A²: their charge's variance over the prefix). The normal equations divided by the density then
    add ``(E / T) / ((G + R) / T²)`` to each column: the prior precision of each level, in seconds of data.
    """
    seconds = float(p["xint"][0, 0])  # the prefix's duration (the integral of the offset column)
    spread = p["G"] + p["R"]
    return np.divide(p["E"] * seconds, spread, out=np.full(2, np.inf), where=spread > 0)


def once_coef(p: dict[str, Any], basis: np.ndarray | None = None, levels: tuple[int, ...] | None = None,
              prior_s: float = 20.0) -> np.ndarray:
    """The posterior mean of ``g + u`` on the update's basis (``basis``: a change of basis, :data:`PARTITION`), with
    :func:`once_penalty` as the ridge of every column, or (``levels``) of those columns only, the others keeping the
    update's ridge ``prior_s``; returned as coefficients of the update's basis."""
    xtx, xtr = p["normal"]
    m = np.eye(4) if basis is None else basis
    out = np.zeros((2, 4))
    for k, pen in enumerate(once_penalty(p)):
        if np.isfinite(pen):
            diag = np.full(4, pen) if levels is None else np.array([pen if j in levels else prior_s for j in range(4)])
            out[k] = m @ np.linalg.solve(m.T @ xtx[k] @ m + np.diag(diag), m.T @ xtr[k])
    return out


def _ground_share(p: dict[str, Any]) -> np.ndarray:
    spread = p["G"] + p["R"]
    return np.divide(p["G"], spread, out=np.zeros(2), where=spread > 0)


def rule_once(p: dict, f: dict) -> np.ndarray:
    """Shrink once: the posterior mean of the run's offset (ridge :func:`once_penalty`), the ground's share ``G / (G +
    R)`` carried to other runs; without a learned ground spread the evidence shrink (as the library)."""
    if not np.any(p["G"] > 0):
        return rule_evidence(p, f)
    return once_coef(p) * _ground_share(p)[:, None]


def rule_partition_once(p: dict, f: dict) -> np.ndarray:
    """:func:`rule_once` on the regime partition: each level's posterior from its own seconds."""
    if not np.any(p["G"] > 0):
        return partition_coef(p) * _prior_or_evidence_factor(p, f)[:, None]
    return once_coef(p, PARTITION) * _ground_share(p)[:, None]


def rule_once_levels(p: dict, f: dict) -> np.ndarray:
    """:func:`rule_once` with the posterior's penalty on the offset only; the regime columns (``|v|``, turning, outer
    turning), which the learned spreads say nothing about apart, keep the update's 20-s ridge."""
    if not np.any(p["G"] > 0):
        return rule_evidence(p, f)
    return once_coef(p, levels=(0,)) * _ground_share(p)[:, None]


def rule_partition_once_levels(p: dict, f: dict) -> np.ndarray:
    """:func:`rule_partition_once` with the posterior's penalty on the two levels (straight, turning) only."""
    if not np.any(p["G"] > 0):
        return partition_coef(p) * _prior_or_evidence_factor(p, f)[:, None]
    return once_coef(p, PARTITION, levels=(0, 2)) * _ground_share(p)[:, None]


def _shares(xint: np.ndarray) -> np.ndarray:
    s = regime_seconds(xint)
    return s / max(float(s.sum()), 1e-12)


def rule_overlap_prior(p: dict, f: dict) -> Callable[[dict[str, Any]], np.ndarray]:
    """Candidate (b): the default, applied to each scored run in proportion to the regime overlap of prefix and run,
    ``sum_j min(p_j, q_j)`` over the shares of time straight and turning (1 when they drove alike)."""
    c, ps = rule_prior(p, f), _shares(p["xint"])
    return lambda rb: c * float(np.sum(np.minimum(ps, _shares(rb["xint"]))))


def rule_overlap_regime_prior(p: dict, f: dict) -> Callable[[dict[str, Any]], np.ndarray]:
    """Candidate (b) per regime: the default's straight level (and its |v| term) scaled by ``min(1, p_s / q_s)``, its
    turning level (and outer term) by ``min(1, p_t / q_t)`` — a regime the prefix drove less than the run is moved less."""
    c, ps = rule_prior(p, f), _shares(p["xint"])
    levels = np.linalg.solve(PARTITION, c.T).T  # the default's coefficients as partition levels

    def at(rb: dict[str, Any]) -> np.ndarray:
        w = np.minimum(1.0, ps / np.maximum(_shares(rb["xint"]), 1e-12))
        return (PARTITION @ (levels * w[[0, 0, 1, 1]]).T).T

    return at


def switch_rule(theta: float) -> Rule:
    """Candidate (c): the partition (with the default's factor) where the prefix's balance is below ``theta``, else
    the default."""
    return lambda p, f: rule_partition_prior(p, f) if balance(p["xint"]) < theta else rule_prior(p, f)


def scale_rule(c: float) -> Rule:
    """The plain update scaled by ``c`` on both sides."""
    return lambda p, f: p["coef"] * c


def penalty_rule(prior_s: float) -> Rule:
    """The plain update with the ridge penalty ``prior_s`` (s of data showing no residual)."""
    return lambda p, f: ridge(p, prior_s)


#: Balances below which candidate (c) takes the partition: 0 never (the default), 1.01 always (ties go to the first).
SWITCH_GRID = (0.0, *np.round(np.arange(0.05, 1.0001, 0.05), 2).tolist(), 1.01)
#: Rule families with one free constant, chosen on the inner folds (the held-out ground never seen).
FAMILIES: dict[str, dict[float, Rule]] = {
    "scale (LOGO)": {c: scale_rule(c) for c in np.round(np.linspace(0.0, 1.0, 11), 2)},
    "penalty (LOGO)": {s_: penalty_rule(s_) for s_ in (20.0, 40.0, 80.0, 160.0, 320.0, 640.0, 1280.0, 1e9)},
    "switch (LOGO)": {th: switch_rule(th) for th in SWITCH_GRID},
}
#: Families chosen like the candidates (:func:`held_out_choice`): on the *other* grounds' few-shot folds.
OTHERS_FAMILIES: dict[str, dict[float, Rule]] = {"switch (others)": {th: switch_rule(th) for th in SWITCH_GRID}}


def choose(rules: dict[float, Rule], folds: list[dict[str, Any]], tie_pts: float = 1.0) -> float:
    """The constant whose worst harm over ``folds`` (median or p90, 20 and 40 s) is least; ties within ``tie_pts``
    broken by the lower mean error (the choice rule of the defaults)."""
    scored = {k: harm(r, folds) for k, r in rules.items()}
    best = min(v[0] for v in scored.values())
    return min((k for k, v in scored.items() if v[0] <= best + tie_pts), key=lambda k: scored[k][1])


def charges(rule: Rule, fold: dict[str, Any]) -> list[dict[str, Any]]:
    """Per (prefix, scored run): the total-charge error % of the rule, unadapted and the gain baseline."""
    rows = []
    runs = fold["runs"]
    for p in fold["prefixes"]:
        coef, key = _resolve(rule(p, fold))
        for b, rb in enumerate(runs):
            if b == p["a"]:
                continue
            q_true = float(np.sum(rb["q_true"]))
            side = rb["q_base"] + np.sum(_at(coef, rb) * rb[key], axis=1)
            rows.append({"a": p["a"], "b": b, "T": p["T"], "q_true": q_true,
                         "err": 100.0 * abs(float(np.sum(side)) - q_true) / q_true,
                         "err_side": 100.0 * (side - rb["q_true"]) / q_true,
                         "base": 100.0 * abs(float(np.sum(rb["q_base"])) - q_true) / q_true,
                         "gain": 100.0 * abs(float(np.sum(rb["q_base"] * p["gain"])) - q_true) / q_true})
    return rows


def summary(rows: list[dict[str, Any]], key: str, T: float) -> tuple[float, float]:
    e = np.array([r[key] for r in rows if r["T"] == T])
    return (float(np.median(e)), float(np.percentile(e, 90))) if e.size else (np.nan, np.nan)


def harm(rule: Rule, folds: list[dict[str, Any]], Ts: tuple[float, ...] = (20.0, 40.0)) -> tuple[float, float]:
    """Worst rise over the folds (median or p90 at each T) above the unadapted forecast, and the mean error."""
    worst, errs = -np.inf, []
    for f in folds:
        rows = charges(rule, f)
        for T in Ts:
            m, p9 = summary(rows, "err", T)
            bm, bp = summary(rows, "base", T)
            if np.isfinite(m):
                worst = max(worst, m - bm, p9 - bp)
                errs += [m, p9]
    return float(worst), float(np.mean(errs)) if errs else np.nan


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", choices=("borealtc", "generated"), default="borealtc")
    ap.add_argument("--path", type=Path, default=DATA, help="the BorealTC folder")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--adapt-seconds", type=float, nargs="+", default=[10.0, 20.0, 40.0])
    ap.add_argument("--no-inner", action="store_true", help="outer folds only")
    ap.add_argument("--cache", type=Path, help="pickle of the fitted folds' charges: built when missing, read when there")
    ap.add_argument("--out", type=Path, help="JSON of every number")
    ap.add_argument("--choice-cache", type=Path,
                    help="another data set's cache: the update and the constants are chosen on its grounds (this data "
                         "set held out of every choice)")
    args = ap.parse_args(argv)
    Ts = tuple(args.adapt_seconds)
    cache = None
    if args.cache is not None and args.cache.exists():
        cache = pickle.loads(args.cache.read_bytes())
        if cache.get("version") != CACHE_VERSION:
            ap.error(f"{args.cache} is a cache of version {cache.get('version')!r}, not {CACHE_VERSION}: delete it")

    def save(c: dict[str, Any]) -> None:
        if args.cache is not None:
            args.cache.parent.mkdir(parents=True, exist_ok=True)
            tmp = args.cache.with_suffix(".tmp")
            tmp.write_bytes(pickle.dumps(c))
            tmp.replace(args.cache)

    if cache is None or not cache.get("complete", True):
        t0 = time.perf_counter()
        cache = build_cache(load_logs(args.data, args.path, args.seed), args.seed, Ts, not args.no_inner, cache, save)
        print(f"cache built in {time.perf_counter() - t0:.0f} s")
    choice = None
    if args.choice_cache is not None:
        other = pickle.loads(args.choice_cache.read_bytes())
        if other.get("version") != CACHE_VERSION:
            ap.error(f"{args.choice_cache} is a cache of version {other.get('version')!r}, not {CACHE_VERSION}")
        choice = list(other["outer"].values())
    report(cache, Ts, args.out, choice)
    return 0


COLUMNS = ("offset", "|v|", "turning", "outer turning")


def diagnose(fold: dict[str, Any], rule: Rule, T: float, top: int = 3) -> dict[str, Any]:
    """Where a rule harms one held-out ground at one T: per prefix, the mean rise of the total-charge error over
    its scored runs, the side errors, the correction per regime column and how the prefix was driven."""
    rows = [r for r in charges(rule, fold) if r["T"] == T]
    runs = fold["runs"]
    per = []
    for p in (q for q in fold["prefixes"] if q["T"] == T):
        mine = [r for r in rows if r["a"] == p["a"]]
        coef, key = _resolve(rule(p, fold))
        parts = np.mean([_at(coef, runs[r["b"]]) * runs[r["b"]][key] / r["q_true"] * 100.0 for r in mine],
                        axis=0)  # (2, 4) % of charge
        coef = np.mean([_at(coef, runs[r["b"]]) for r in mine], axis=0)
        per.append({"prefix": runs[p["a"]]["name"], "harm_pts": float(np.mean([r["err"] - r["base"] for r in mine])),
                    "signed_base_pct": float(np.mean([100.0 * (np.sum(runs[r["b"]]["q_base"]) - r["q_true"]) / r["q_true"]
                                                      for r in mine])),
                    "correction_pct": parts.tolist(), "side_correction_pct": parts.sum(axis=1).tolist(),
                    "prefix_residual_pct": (100.0 * p["obs"] / np.maximum(np.abs(p["xint"][:, 0]), 1e-9)).tolist(),
                    "lam": [float(np.linalg.norm(c) / max(np.linalg.norm(c0), 1e-12)) for c, c0 in zip(coef, p["coef"])],
                    "prefix_stats": p["stats"]})
    per.sort(key=lambda d: -d["harm_pts"])
    scored = {k: float(np.mean([r["stats"][k] for r in runs])) for k in runs[0]["stats"]}
    return {"T": T, "mean_harm_pts": float(np.mean([d["harm_pts"] for d in per])) if per else np.nan,
            "harmed_prefixes": sum(d["harm_pts"] > 0 for d in per), "n_prefixes": len(per),
            "scored_stats": scored, "prefix_stats_mean": {k: float(np.mean([d["prefix_stats"][k] for d in per]))
                                                           for k in scored} if per else {},
            "worst": per[:top], "best": per[-top:]}


def _print_diagnosis(g: str, d: dict[str, Any]) -> None:
    s, ps = d["scored_stats"], d["prefix_stats_mean"]
    print(f"\n{g}, T = {d['T']:g} s: mean harm {d['mean_harm_pts']:+.1f} points, {d['harmed_prefixes']} of "
          f"{d['n_prefixes']} prefixes harm; motion |v| / turning / rest: prefixes {ps['v_mps']:.2f} / "
          f"{ps['turning']:.2f} / {ps['rest']:.2f}, whole runs {s['v_mps']:.2f} / {s['turning']:.2f} / {s['rest']:.2f}")
    for tag, items in (("worst", d["worst"]), ("best", d["best"])):
        for w in items:
            c = np.asarray(w["correction_pct"])
            print(f"  {tag:5s} {w['prefix']:24s} harm {w['harm_pts']:+6.1f}  unadapted signed {w['signed_base_pct']:+6.1f} %  "
                  f"correction L/R {c[0].sum():+6.1f} / {c[1].sum():+6.1f} % (columns, both sides: "
                  + ", ".join(f"{n} {v:+.1f}" for n, v in zip(COLUMNS, c.sum(axis=0)))
                  + f")  prefix |v| {w['prefix_stats']['v_mps']:.2f} turning {w['prefix_stats']['turning']:.2f}")


def clamp_effect(fold: dict[str, Any]) -> float:
    """Largest difference (points of total charge) between the cached plain update and the exact, clamped one."""
    worst = 0.0
    for p in fold["prefixes"]:
        for b, rb in enumerate(fold["runs"]):
            if b != p["a"]:
                lin = rb["q_base"] + np.sum(p["coef"] * rb["xint"], axis=1)
                worst = max(worst, 100.0 * abs(float(np.sum(lin - fold["pairs"][(p["a"], p["T"], b)]))) / float(np.sum(rb["q_true"])))
    return worst


def table(cache: dict[str, Any], rules: dict[str, Rule], Ts: tuple[float, ...],
          choice_folds: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """Per outer ground (then pooled) and T: median / p90 % of every rule, unadapted and the gain baseline; the
    families' constants chosen per outer ground on its inner folds, :data:`OTHERS_FAMILIES`' on the other grounds'
    folds or, given, on ``choice_folds`` (another data set's: this one held out of every choice) (``chosen``)."""
    out: dict[str, Any] = {"chosen": {}}
    pooled: dict[str, list[dict[str, Any]]] = {}
    for g, fold in cache["outer"].items():
        out[g] = {}
        here = dict(rules)
        inner = list(cache["inner"].get(g, {}).values())
        for fam, members in FAMILIES.items():
            if inner:
                k = choose(members, inner)
                out["chosen"].setdefault(fam, {})[g] = float(k)
                here[fam] = members[k]
        others = choice_folds if choice_folds is not None else [f for h, f in cache["outer"].items() if h != g]
        for fam, members in OTHERS_FAMILIES.items():
            if others:
                k = choose(members, others)
                out["chosen"].setdefault(fam, {})[g] = float(k)
                here[fam] = members[k]
        for name, rule in here.items():
            rows = charges(rule, fold)
            pooled.setdefault(name, []).extend(rows)
            out[g][name] = {f"{T:g}": summary(rows, "err", T) for T in Ts}
        rows = charges(rule_unadapted, fold)
        pooled.setdefault("gain", []).extend(rows)
        out[g]["gain"] = {f"{T:g}": summary(rows, "gain", T) for T in Ts}
    out["all"] = {name: {f"{T:g}": summary(rows, "gain" if name == "gain" else "err", T) for T in Ts}
                  for name, rows in pooled.items()}
    return out


#: The updates the held-out choice picks among (the default first).
CANDIDATES = ("prior", "evidence", "none", "partition", "partition, prior", "hierarchical, prior", "overlap, prior",
              "overlap per regime, prior", "once", "partition, once", "once, levels", "partition, once, levels")


def held_out_choice(cache: dict[str, Any], rules: dict[str, Rule],
                    choice_folds: list[dict[str, Any]] | None = None) -> dict[str, str]:
    """Per ground, the candidate :func:`choose` picks on the *other* grounds' few-shot folds (this one never seen), or
    on ``choice_folds``."""
    out = {}
    for g in cache["outer"]:
        others = choice_folds if choice_folds is not None else [f for h, f in cache["outer"].items() if h != g]
        names = list(CANDIDATES)
        pick = choose(dict(enumerate(rules[n] for n in names)), others)
        out[g] = names[int(pick)]
    return out


def report(cache: dict[str, Any], Ts: tuple[float, ...], out: Path | None,
           choice_folds: list[dict[str, Any]] | None = None) -> None:
    rules = {"unadapted": rule_unadapted, "none": rule_none, "evidence": rule_evidence, "prior": rule_prior,
             "prior, moving": rule_prior_moving, "partition": rule_partition,
             "partition, prior": rule_partition_prior, "partition, moving, prior": rule_partition_moving_prior,
             "hierarchical, prior": rule_hierarchical_prior, "overlap, prior": rule_overlap_prior,
             "overlap per regime, prior": rule_overlap_regime_prior,
             "once": rule_once, "partition, once": rule_partition_once,
             "once, levels": rule_once_levels, "partition, once, levels": rule_partition_once_levels,
             "regime gain": rule_regime_gain, "regime gain, prior": rule_regime_gain_prior}
    print("clamp left out of the cached charges, worst points per ground: " +
          ", ".join(f"{g} {clamp_effect(f):.2f}" for g, f in cache["outer"].items()))
    diag = {g: [diagnose(f, rule_prior, T) for T in Ts if T >= 20] for g, f in cache["outer"].items()}
    for g, ds in diag.items():
        for d in ds:
            _print_diagnosis(g, d)
    tab = table(cache, rules, Ts, choice_folds)
    tab["intervals"] = interval_table(cache, rule_partition_prior, Ts)
    print("coverage of the 50 / 80 / 95 % intervals of total charge, median |z|, mean log score (the default update, "
          "partition + prior):")
    for g, per in tab["intervals"].items():
        u = per["unadapted"]
        print(f"{g:10s} unadapted {u[0]:5.1f} / {u[1]:5.1f} / {u[2]:5.1f}  |z| {u[3]:.2f}  log {u[4]:.3f}")
        for name in INTERVAL_RULES:
            print(f"{g:10s} {name:16s} " + "   ".join(
                "{:5.1f} / {:5.1f} / {:5.1f}  |z| {:.2f}  log {:.3f}".format(*per[name][f"{T:g}"]) for T in Ts))
    tab["held_out_choice"] = (held_out_choice(cache, rules, choice_folds)
                              if len(cache["outer"]) > 2 or choice_folds is not None else {})
    print("update chosen on the other grounds or --choice-cache (worst harm at 20 / 40 s, ties within 1 point by the mean error): "
          + ", ".join(f"{g}: {n}" for g, n in tab["held_out_choice"].items()))
    print("\ntotal charge median / p90 % per T " + " ".join(f"{T:g} s" for T in Ts))
    print("constants chosen (LOGO: on the inner folds; others: on the other grounds or --choice-cache): " + "; ".join(f"{fam}: {v}" for fam, v in tab["chosen"].items()))
    for g, per in tab.items():
        if g in ("chosen", "held_out_choice", "intervals"):
            continue
        for name, cells in per.items():
            print(f"{g:10s} {name:12s} " + "   ".join("{:6.1f} / {:6.1f}".format(*cells[f"{T:g}"]) for T in Ts))
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps({"table": tab, "diagnosis": diag}, indent=1, default=float) + "\n")
        print(f"wrote {out}")


if __name__ == "__main__":
    raise SystemExit(main())
