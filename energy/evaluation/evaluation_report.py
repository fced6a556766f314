"""Current models of named kinds evaluated on logs by one protocol: the entry point of ``terrawatt evaluate``."""

from __future__ import annotations

import dataclasses
import numbers
import time
from collections.abc import Sequence

from terrawatt_base.checks import check_choice, check_instance
from terrawatt_base.dask_client import Compute
from terrawatt_base.errors import InvalidParameterError

from ..logs import InteractionLog
from ..models.adaptation import ADAPT_METHODS, ADAPT_SHRINKS
from ..models.base import check_logs
from ..models.kinds import CURRENT_MODEL_KINDS
from ..models.training_report import ModelOptions
from .adapt_protocol import DEFAULT_ADAPT_SECONDS, AdaptSettings, evaluate_adaptation
from .few_shot import evaluate_few_shot
from .results import EVALUATION_PROTOCOLS, EVALUATION_VARIANTS, EvaluationResult
from .scoring import evaluate_current_models

__all__ = ["check_adapt_options", "check_evaluation_options", "evaluate_kinds"]


def check_adapt_options(protocol: str = "adapt", *, adapt_seconds: Sequence[float] = DEFAULT_ADAPT_SECONDS,
                        adapt_method: str = ADAPT_METHODS[0], adapt_threshold_pct: float = 10.0,
                        adapt_shrink: str = ADAPT_SHRINKS[0]) -> AdaptSettings:
    """The :class:`AdaptSettings` of the adapt options, checked; the trigger schedule runs with ``protocol="adapt"``.

    The errors name the option they are about (:attr:`~terrawatt_base.errors.TerrawattError.parameter`:
    a front end says it in its own words, e.g. the command line by its flag).

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
    >>> check_adapt_options(adapt_seconds=[10, 0])
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: adapt_seconds must be seconds > 0, got 0
    """
    check_choice("protocol", protocol, EVALUATION_PROTOCOLS)
    seconds = [adapt_seconds] if isinstance(adapt_seconds, numbers.Real) else list(adapt_seconds)
    if bad := [t for t in seconds if isinstance(t, bool) or not isinstance(t, numbers.Real) or not t > 0]:
        raise InvalidParameterError(f"adapt_seconds must be seconds > 0, got {bad[0]!r}", parameter="adapt_seconds")
    least = AdaptSettings.min_seconds  # the update's own minimum of driving in its prefix
    if bad := [t for t in seconds if t <= least]:
        raise InvalidParameterError(
            f"adapt_seconds {bad[0]:g}: the update needs more than {least:g} s of driving in the seconds it "
            f"adapts on, so no run could adapt on {bad[0]:g} s; give seconds > {least:g}, e.g. 10 20 40",
            parameter="adapt_seconds")
    threshold = adapt_threshold_pct
    if isinstance(threshold, bool) or not isinstance(threshold, numbers.Real) or not threshold >= 0:
        raise InvalidParameterError(f"adapt_threshold_pct must be a percentage >= 0, got {threshold!r}",
                                    parameter="adapt_threshold_pct")
    check_choice("adapt_method", adapt_method, ADAPT_METHODS)
    check_choice("adapt_shrink", adapt_shrink, ADAPT_SHRINKS)
    return AdaptSettings(adapt_seconds=tuple(seconds), method=adapt_method, threshold_pct=threshold,
                         shrink=adapt_shrink, trigger=protocol == "adapt")


def check_evaluation_options(kinds: Sequence[str] | None = None, *, protocol: str = "loo",
                             options: ModelOptions | None = None) -> tuple[str, ...]:
    """Check the kinds, protocol and model options of :func:`evaluate_kinds` before any work; return the kinds
    evaluated.

    Parameters
    ----------
    kinds : sequence of str, optional
        Model kinds (:data:`~energy.models.CURRENT_MODEL_KINDS`; one named twice is evaluated once);
        default every kind for ``"loo"``, the estimator for the adapt protocols.
    protocol : str
        One of :data:`EVALUATION_PROTOCOLS`.
    options : ModelOptions, optional
        How the models are made: a band needs a learned kind among ``kinds``, a robot the physics kind.

    Returns
    -------
    tuple of str

    Raises
    ------
    InvalidParameterError
        No kinds, a band for baselines only, a robot without the physics kind, options that are no
        :class:`~energy.models.ModelOptions`.
    UnknownNameError
        An unknown protocol or kind.

    Examples
    --------
    >>> check_evaluation_options(protocol="adapt")
    ('estimator',)
    """
    check_choice("protocol", protocol, EVALUATION_PROTOCOLS)
    options = ModelOptions() if options is None else check_instance("options", options, ModelOptions)
    if kinds is None:
        kinds = CURRENT_MODEL_KINDS if protocol == "loo" else ("estimator",)
    given = [kinds] if isinstance(kinds, str) else list(kinds)
    if not given:
        raise InvalidParameterError("kinds must name at least one model kind, got none", parameter="kinds")
    for k in given:
        check_choice("kinds", k, CURRENT_MODEL_KINDS)
    options.check_kinds(given)
    return tuple(dict.fromkeys(given))


def _check_runs_long_enough(items: Sequence[InteractionLog], settings: AdaptSettings, protocol: str) -> None:
    """Before any training: every adapt time T leaves some run to score (``"adapt"``: T plus the scored
    remainder; ``"few-shot"``: T itself), else the table of T would be empty."""
    need_after = settings.min_remainder_s if protocol == "adapt" else 0.0
    longest = max(log.duration_s for log in items)
    if bad := [t for t in settings.adapt_seconds if t + need_after > longest]:
        what = f"{bad[0]:g} s plus the {need_after:g} s scored after them" if need_after else f"{bad[0]:g} s"
        raise InvalidParameterError(
            f"adapt_seconds {bad[0]:g}: no run lasts {what} (the longest lasts {longest:.1f} s), so nothing would be "
            f"scored; give seconds up to {max(longest - need_after, 0.0):.1f}", parameter="adapt_seconds")


def evaluate_kinds(logs: Sequence[InteractionLog], kinds: Sequence[str] | None = None, *, protocol: str = "loo",
                   variants: Sequence[str] = EVALUATION_VARIANTS, settings: AdaptSettings | None = None,
                   options: ModelOptions | None = None, compute: Compute | None = None) -> EvaluationResult:
    """New models of ``kinds`` (:meth:`ModelOptions.new_model <energy.models.ModelOptions.new_model>`) evaluated on
    ``logs`` by ``protocol``: the result with its header (the kinds, the logs, the wall time).

    ``"loo"``: leave one run out (:func:`evaluate_current_models`, over ``variants``);
    ``"adapt"``: also adapt each held-out run's model on its first seconds
    (:func:`evaluate_adaptation`); ``"few-shot"``: train on the other grounds and adapt on
    seconds of one run of a ground (:func:`evaluate_few_shot`).

    Parameters
    ----------
    logs : sequence of InteractionLog
        Runs with measured currents and ground labels.
    kinds, protocol, options
        As :func:`check_evaluation_options`; ``options`` default :class:`~energy.models.ModelOptions` ``()``
        (seed 0, the kinds' own band, husky).
    variants : sequence of str
        ``"loo"``: the variants (:data:`EVALUATION_VARIANTS`).
    settings : AdaptSettings, optional
        The adapt protocols' settings (:func:`check_adapt_options`; default its defaults, the
        trigger with ``"adapt"``); none for ``"loo"``.
    compute : Compute, optional
        Where the folds run and whether a bar shows over them (:class:`terrawatt_base.dask_client.Compute`;
        default here, no bar).

    Returns
    -------
    EvaluationResult

    Raises
    ------
    InvalidParameterError, UnknownNameError
        As :func:`check_evaluation_options`; settings with ``"loo"``, or not an AdaptSettings; adapt
        seconds longer than every run.
    TerrawattError
        As the protocol's function.
    """
    options = ModelOptions() if options is None else check_instance("options", options, ModelOptions)
    kinds = check_evaluation_options(kinds, protocol=protocol, options=options)
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    if protocol == "loo" and settings is not None:
        raise InvalidParameterError("settings applies to the adapt and few-shot protocols, got protocol 'loo'",
                                    parameter=("settings", "protocol"))
    if protocol != "loo":
        settings = check_adapt_options(protocol) if settings is None else settings
        if not isinstance(settings, AdaptSettings):
            raise InvalidParameterError(f"settings must be an AdaptSettings, got {settings!r:.80}", parameter="settings")
    items = check_logs(logs)
    if protocol != "loo":
        _check_runs_long_enough(items, settings, protocol)
    models = {k: options.new_model(k) for k in kinds}
    t0 = time.perf_counter()
    with compute.session() as (client, _):
        if protocol == "loo":
            result = evaluate_current_models(items, models, variants=variants, progress=compute.progress, client=client)
        else:
            run = evaluate_adaptation if protocol == "adapt" else evaluate_few_shot
            result = run(items, models, settings=settings, progress=compute.progress, client=client)
    return dataclasses.replace(result, kinds=kinds, logs=tuple(items), duration_s=time.perf_counter() - t0)
