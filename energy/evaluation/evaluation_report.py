"""Current models of named kinds evaluated on logs by one protocol, and reported: the scores, their files, a figure."""

from __future__ import annotations

import numbers
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from terrawatt_base.atomic import save_figure
from terrawatt_base.checks import check_choice, check_instance, check_seed, option_names
from terrawatt_base.dask_client import Compute
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.figure_file import draw_figure

from ..logs import InteractionLog
from ..models.adaptation import ADAPT_METHODS, ADAPT_SHRINKS
from ..models.base import check_logs
from ..models.kinds import CURRENT_MODEL_KINDS, LEARNED_KINDS, new_current_model
from ..models.training_report import check_learned_band
from ..params import robot_params
from ..plots import plot_vibration_spectra
from .adapt_protocol import DEFAULT_ADAPT_SECONDS, AdaptSettings, evaluate_adaptation
from .adapt_results import ADAPT_FILES, AdaptationResult
from .few_shot import evaluate_few_shot
from .results import EVALUATION_FILES, EVALUATION_VARIANTS, EvaluationResult
from .scoring import evaluate_current_models

__all__ = ["EVALUATION_PROTOCOLS", "EVALUATION_NAMES", "SPECTRA_FILE", "evaluation_files", "check_adapt_options",
           "check_evaluation_options", "EvaluationReport", "evaluate_report"]

#: The protocols: leave one run out, adapt on each held-out run's first seconds, few shots on a ground left out.
EVALUATION_PROTOCOLS = ("loo", "adapt", "few-shot")
#: How messages name the options of :func:`evaluate_report` (a caller passes its own, e.g. its flags).
EVALUATION_NAMES = {"kinds": "kinds", "protocol": "protocol", "band_hz": "band_hz", "adapt_seconds": "adapt_seconds",
                    "adapt_method": "adapt_method", "adapt_threshold_pct": "adapt_threshold_pct",
                    "adapt_shrink": "adapt_shrink", "robot": "robot"}
#: The figure of the leave-one-run-out report: the logs' vibration spectra per ground.
SPECTRA_FILE = "spectra.png"
#: The reliability figure of every protocol: observed against nominal coverage of the held-out total charge's
#: intervals per protocol, ground and forecast.
RELIABILITY_FILE = "reliability.png"


def evaluation_files(protocol: str = "loo") -> tuple[str, ...]:
    """The files :meth:`EvaluationReport.write` writes for ``protocol`` (the figure last).

    Examples
    --------
    >>> evaluation_files("loo"), evaluation_files("adapt")
    (('evaluation.json', 'evaluation.md', 'spectra.png', 'reliability.png'), ('adapt.json', 'adapt.md', 'reliability.png'))
    """
    check_choice("protocol", protocol, EVALUATION_PROTOCOLS)
    return (*EVALUATION_FILES, SPECTRA_FILE, RELIABILITY_FILE) if protocol == "loo" else (*ADAPT_FILES, RELIABILITY_FILE)


def check_adapt_options(protocol: str = "adapt", *, adapt_seconds: Sequence[float] = DEFAULT_ADAPT_SECONDS,
                        adapt_method: str = ADAPT_METHODS[0], adapt_threshold_pct: float = 10.0,
                        adapt_shrink: str = ADAPT_SHRINKS[0], names: Mapping[str, str] | None = None) -> AdaptSettings:
    """The :class:`AdaptSettings` of the adapt options, checked; the trigger schedule runs with ``protocol="adapt"``.

    Parameters
    ----------
    protocol : str
        One of :data:`EVALUATION_PROTOCOLS`.
    adapt_seconds : sequence of float
        Seconds of each run the model adapts on (each > 0).
    adapt_method : str
        The in-run update (:data:`~energy.models.ADAPT_METHODS`).
    adapt_threshold_pct : float
        The running charge error (%, >= 0) above which the trigger schedule updates.
    adapt_shrink : str
        How the update's correction is scaled by the evidence of its prefix
        (:data:`~energy.models.ADAPT_SHRINKS`; :class:`~energy.models.AdaptedCurrentModel` ``shrink``).
    names : mapping, optional
        How messages name the options (keys of :data:`EVALUATION_NAMES`, e.g. ``{"adapt_seconds": "--adapt-seconds"}``).

    Returns
    -------
    AdaptSettings

    Raises
    ------
    InvalidParameterError
        Seconds not > 0, a negative threshold; as :class:`AdaptSettings`.
    UnknownNameError
        An unknown protocol or method.

    Examples
    --------
    >>> check_adapt_options("few-shot", adapt_seconds=[10]).trigger
    False
    >>> check_adapt_options(adapt_seconds=[10, 0], names={"adapt_seconds": "--adapt-seconds"})
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: --adapt-seconds must be seconds > 0, got 0
    """
    n = option_names(names, EVALUATION_NAMES)
    check_choice(n["protocol"], protocol, EVALUATION_PROTOCOLS)
    seconds = [adapt_seconds] if isinstance(adapt_seconds, numbers.Real) else list(adapt_seconds)
    if bad := [t for t in seconds if isinstance(t, bool) or not isinstance(t, numbers.Real) or not t > 0]:
        raise InvalidParameterError(f"{n['adapt_seconds']} must be seconds > 0, got {bad[0]!r}")
    least = AdaptSettings.min_seconds  # the update's own minimum of driving in its prefix
    if bad := [t for t in seconds if t <= least]:
        raise InvalidParameterError(
            f"{n['adapt_seconds']} {bad[0]:g}: the update needs more than {least:g} s of driving in the seconds it "
            f"adapts on, so no run could adapt on {bad[0]:g} s; give seconds > {least:g}, e.g. 10 20 40")
    threshold = adapt_threshold_pct
    if isinstance(threshold, bool) or not isinstance(threshold, numbers.Real) or not threshold >= 0:
        raise InvalidParameterError(f"{n['adapt_threshold_pct']} must be a percentage >= 0, got {threshold!r}")
    check_choice(n["adapt_method"], adapt_method, ADAPT_METHODS)
    check_choice(n["adapt_shrink"], adapt_shrink, ADAPT_SHRINKS)
    return AdaptSettings(adapt_seconds=tuple(seconds), method=adapt_method, threshold_pct=threshold,
                         shrink=adapt_shrink, trigger=protocol == "adapt")


def check_evaluation_options(kinds: Sequence[str] | None = None, *, protocol: str = "loo",
                             band_hz: Sequence[float] | None = None, robot: Any = None,
                             names: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """Check the kinds, protocol and band of :func:`evaluate_report` before any work; return the kinds evaluated.

    Parameters
    ----------
    kinds : sequence of str, optional
        Model kinds (:data:`~energy.models.CURRENT_MODEL_KINDS`; one named twice is evaluated once);
        default every kind for ``"loo"``, the estimator for the adapt protocols.
    protocol : str
        One of :data:`EVALUATION_PROTOCOLS`.
    band_hz : pair of float, optional
        The learned kinds' vibration band (Hz); one of ``kinds`` must be learned.
    robot : str, path or RobotParams, optional
        The physics kind's robot (:func:`energy.params.robot_params`; default husky); ``kinds`` must hold physics.
    names : mapping, optional
        How messages name the options (keys of :data:`EVALUATION_NAMES`).

    Returns
    -------
    tuple of str

    Raises
    ------
    InvalidParameterError
        No kinds, a bad band or one for baselines only, a robot without the physics kind.
    UnknownNameError
        An unknown protocol or kind, a robot that is no preset nor robot file.
    FileFormatError
        A robot file that does not read.

    Examples
    --------
    >>> check_evaluation_options(protocol="adapt")
    ('estimator',)
    """
    n = option_names(names, EVALUATION_NAMES)
    check_choice(n["protocol"], protocol, EVALUATION_PROTOCOLS)
    if kinds is None:
        kinds = CURRENT_MODEL_KINDS if protocol == "loo" else ("estimator",)
    given = [kinds] if isinstance(kinds, str) else list(kinds)
    if not given:
        raise InvalidParameterError(f"{n['kinds']} must name at least one model kind, got none")
    for k in given:
        check_choice(n["kinds"], k, CURRENT_MODEL_KINDS)
    check_learned_band(band_hz, given, name=n["band_hz"], kinds_name=n["kinds"])
    if robot is not None:
        if "physics" not in given:
            raise InvalidParameterError(f"{n['robot']} is the physics model's robot; {n['kinds']} "
                                        f"{' '.join(given)} has no physics")
        robot_params(robot, name=n["robot"])
    return tuple(dict.fromkeys(given))


@dataclass(frozen=True)
class EvaluationReport:
    """Current models of named kinds scored on logs by one protocol, ready to print and write.

    Made by :func:`evaluate_report`. :meth:`summary` is the table ``terrawatt evaluate``
    prints, :meth:`write` writes :func:`evaluation_files`, :meth:`written_line` says what.

    Attributes
    ----------
    result : EvaluationResult or AdaptationResult
        The scores (leave one run out, or an adapt protocol).
    protocol : str
        One of :data:`EVALUATION_PROTOCOLS`.
    kinds : tuple of str
        The model kinds evaluated.
    logs : tuple of InteractionLog
        The runs.
    duration_s : float
        Wall time of the evaluation, s.
    """

    result: EvaluationResult | AdaptationResult
    protocol: str
    kinds: tuple[str, ...]
    logs: tuple[InteractionLog, ...]
    duration_s: float

    def summary(self) -> str:
        """The markdown table of the scores (:meth:`EvaluationResult.to_markdown`)."""
        return self.result.to_markdown()

    def to_dict(self) -> dict[str, Any]:
        """The content of the JSON file: the result's document."""
        return self.result.to_dict()

    def written_line(self, written: Sequence[Path], *, workers: str = "1 worker (serial)") -> str:
        """Runs, models, time and ``workers`` (where the folds ran), and the files :meth:`write` wrote (``written``)."""
        names = [str(p) for p in written]
        files = ", ".join(names) if self.protocol != "loo" or len(names) < 2 else (
            ", ".join(names[:-1]) + " and " + names[-1])
        return (f"{len(self.logs)} runs, {len(self.kinds)} models, {self.duration_s:.1f} s on {workers}; "
                f"wrote {files}")

    def write(self, out_dir: str | os.PathLike[str], *, on_figure_error: str = "warn") -> list[Path]:
        """Write the result's JSON and markdown into ``out_dir`` (created), leaving one run out the logs'
        vibration spectra (:data:`SPECTRA_FILE`), and the reliability of the total charge's intervals
        (:data:`RELIABILITY_FILE`); return the files written.

        A figure that fails warns (:class:`~terrawatt_base.errors.FigureWarning`) and is left out,
        unless ``on_figure_error="raise"``.
        """
        check_choice("on_figure_error", on_figure_error, ("warn", "raise"))
        out = Path(out_dir)
        written = [*self.result.write(out)]
        figures = [(out / RELIABILITY_FILE, lambda p: save_figure(self.result.plot_reliability().figure, p))]
        if self.protocol == "loo":
            figures.insert(0, (out / SPECTRA_FILE, lambda p: plot_vibration_spectra(list(self.logs), p)))
        for png, draw in figures:
            done = draw_figure(png, lambda png=png, draw=draw: draw(png), on_error=on_figure_error)
            if done is not None:
                written.append(done)
        return written


def _check_runs_long_enough(items: Sequence[InteractionLog], settings: AdaptSettings, protocol: str, flag: str) -> None:
    """Before any training: every adapt time T leaves some run to score (``"adapt"``: T plus the scored
    remainder; ``"few-shot"``: T itself), else the table of T would be empty."""
    need_after = settings.min_remainder_s if protocol == "adapt" else 0.0
    longest = max(log.duration_s for log in items)
    if bad := [t for t in settings.adapt_seconds if t + need_after > longest]:
        what = f"{bad[0]:g} s plus the {need_after:g} s scored after them" if need_after else f"{bad[0]:g} s"
        raise InvalidParameterError(
            f"{flag} {bad[0]:g}: no run lasts {what} (the longest lasts {longest:.1f} s), so nothing would be "
            f"scored; give seconds up to {max(longest - need_after, 0.0):.1f}")


def evaluate_report(logs: Sequence[InteractionLog], kinds: Sequence[str] | None = None, *, protocol: str = "loo",
                    variants: Sequence[str] = EVALUATION_VARIANTS, settings: AdaptSettings | None = None,
                    seed: int | None = 0, band_hz: Sequence[float] | None = None, robot: Any = None,
                    compute: Compute | None = None, names: Mapping[str, str] | None = None) -> EvaluationReport:
    """New models of ``kinds`` (:func:`~energy.models.new_current_model`) evaluated on ``logs`` by ``protocol``.

    ``"loo"``: leave one run out (:func:`evaluate_current_models`, over ``variants``);
    ``"adapt"``: also adapt each held-out run's model on its first seconds
    (:func:`evaluate_adaptation`); ``"few-shot"``: train on the other grounds and adapt on
    seconds of one run of a ground (:func:`evaluate_few_shot`).

    Parameters
    ----------
    logs : sequence of InteractionLog
        Runs with measured currents and ground labels.
    kinds, protocol, band_hz, robot, names
        As :func:`check_evaluation_options`; ``band_hz`` goes to the learned kinds only, ``robot`` to
        the physics kind.
    variants : sequence of str
        ``"loo"``: the variants (:data:`EVALUATION_VARIANTS`).
    settings : AdaptSettings, optional
        The adapt protocols' settings (:func:`check_adapt_options`; default its defaults, the
        trigger with ``"adapt"``); none for ``"loo"``.
    seed : int or None
        Seed of the learned kinds.
    compute : Compute, optional
        Where the folds run and whether a bar shows over them (:class:`terrawatt_base.dask_client.Compute`;
        default here, no bar).

    Returns
    -------
    EvaluationReport

    Raises
    ------
    InvalidParameterError, UnknownNameError
        As :func:`check_evaluation_options`; settings with ``"loo"``, or not an AdaptSettings.
    TerrawattError
        As the protocol's function.
    """
    kinds = check_evaluation_options(kinds, protocol=protocol, band_hz=band_hz, robot=robot, names=names)
    band = check_learned_band(band_hz, kinds, name=option_names(names, EVALUATION_NAMES)["band_hz"])
    seed = check_seed(seed)
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    if protocol == "loo" and settings is not None:
        raise InvalidParameterError("settings applies to the adapt and few-shot protocols, got protocol 'loo'")
    if protocol != "loo":
        settings = check_adapt_options(protocol, names=names) if settings is None else settings
        if not isinstance(settings, AdaptSettings):
            raise InvalidParameterError(f"settings must be an AdaptSettings, got {settings!r:.80}")
    items = check_logs(logs)
    if protocol != "loo":
        _check_runs_long_enough(items, settings, protocol, option_names(names, EVALUATION_NAMES)["adapt_seconds"])
    models = {k: new_current_model(k, seed=seed, band_hz=band if k in LEARNED_KINDS else None,
                                   robot=robot if k == "physics" else None) for k in kinds}
    t0 = time.perf_counter()
    with compute.session() as (client, _):
        if protocol == "loo":
            result: EvaluationResult | AdaptationResult = evaluate_current_models(
                items, models, variants=variants, progress=compute.progress, client=client)
        else:
            run = evaluate_adaptation if protocol == "adapt" else evaluate_few_shot
            result = run(items, models, settings=settings, progress=compute.progress, client=client)
    return EvaluationReport(result, protocol, kinds, tuple(items), time.perf_counter() - t0)
