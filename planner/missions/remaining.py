"""The forecast of what remains of a mission, learning from this run as it goes (the in-run gain and its interval).

The models price the remaining legs (``pending``: each leg's stop-turn-go profile, J). What
this run has measured corrects that price: over the legs driven since the models last
changed, the gain ``g = (sum(actual) + n0 * mean(predicted)) / (sum(predicted) + n0 *
mean(predicted))`` — measured over predicted energy, shrunk toward 1 by ``n0`` prior legs.
The spread ``s`` of a leg's log ratio ``log(actual / predicted)`` about its mean is pooled
over every stretch of this run between model changes (what varies leg to leg does not depend
on the models) and with a prior spread ``s0`` (weight ``n0``). The forecast of the rest is
``E = g * sum(pending)`` with a standard deviation that adds, in quadrature, what the gain does
not know (``E * s / sqrt(n + n0)``: a systematic error over the whole rest), what varies leg to
leg (``g * s * sqrt(sum(pending^2))``) and what no leg of this run has shown: the energy of the
rest on each ground class the robot has not driven yet, ``E_c``, off by a relative spread
``s_u`` as a whole (``s_u * sqrt(sum_c E_c^2)``; a model on a ground it has not seen is off by
37-55 % on the real logs' few-shot protocol, ``s_u`` = 0.4 by default). Central intervals and
the risk quantile are read from the same predictive as the route's energy interval
(:func:`energy.models.forecast.predictive_quantile` with the ``dof`` of the route's
:class:`~planner.RouteEnergyInterval` on the planning cost): the normal distribution where the
models know every ground the rest crosses, a Student-t where one of them was never driven.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from energy.models.forecast import check_dof, predictive_quantile

from .charge import ChargeAccount
from .decisions import RemainingForecast
from .settings import AdaptiveSettings

__all__ = ["remaining_forecast"]


def remaining_forecast(
    pending_j: Sequence[float],
    observed: Sequence[tuple[float, float]],
    settings: AdaptiveSettings,
    charge: ChargeAccount,
    *,
    pooled: tuple[float, float] = (0.0, 0.0),
    unseen_j: Sequence[float] = (),
    dof: float = math.inf,
) -> RemainingForecast:
    """The energy of the remaining legs with the in-run correction (see the module docstring).

    Parameters
    ----------
    pending_j : sequence of float
        The models' price of each remaining leg (J).
    observed : sequence of (predicted_j, actual_j)
        Legs driven since the models last changed.
    settings : AdaptiveSettings
        The forecast's options: the central interval's coverage (``interval_level``), the upper
        quantile decisions use (``risk``; None: the point forecast), ``n0`` and ``s0`` of the
        module docstring (``forecast_prior_legs``, ``forecast_prior_spread``) and ``s_u``
        (``forecast_unseen_spread``).
    charge : ChargeAccount
        The battery's account: its state of charge and energy above the reserve now (J), carried
        into the result.
    pooled : (float, float)
        Sum of squared log-ratio deviations and their degrees of freedom from the run's earlier
        stretches (between model changes).
    unseen_j : sequence of float
        The models' price of the rest on each ground class not driven yet (J).
    dof : float
        Degrees of freedom of the predictive the quantiles are read from (``inf``, the
        default: the normal distribution): the route interval's
        (:attr:`~planner.RouteEnergyInterval.dof`).

    Returns
    -------
    RemainingForecast
    """
    dof = check_dof(dof)
    level, risk = settings.interval_level, settings.risk
    prior_legs, prior_spread = settings.forecast_prior_legs, settings.forecast_prior_spread
    unseen_spread = settings.forecast_unseen_spread
    p = np.asarray([float(x) for x in pending_j], dtype=np.float64)
    obs = np.asarray([(a, b) for a, b in observed if a > 0 and b > 0], dtype=np.float64).reshape(-1, 2)
    n = obs.shape[0]
    model_j = float(p.sum())
    if n:
        mean_pred = float(obs[:, 0].mean())
        gain = (float(obs[:, 1].sum()) + prior_legs * mean_pred) / (float(obs[:, 0].sum()) + prior_legs * mean_pred)
    else:
        gain = 1.0
    ss, ss_dof = float(pooled[0]), float(pooled[1])
    if n >= 2:
        r = np.log(obs[:, 1] / obs[:, 0])
        ss, ss_dof = ss + float(np.sum((r - r.mean()) ** 2)), ss_dof + n - 1
    spread = math.sqrt((prior_legs * prior_spread ** 2 + ss) / (prior_legs + ss_dof))
    energy = gain * model_j
    u = gain * unseen_spread * math.sqrt(float(np.sum(np.square(np.asarray(unseen_j, dtype=np.float64)))))
    sd = math.sqrt((energy * spread / math.sqrt(n + prior_legs)) ** 2 + (gain * spread) ** 2 * float(np.sum(p ** 2))
                   + u ** 2)
    z = predictive_quantile(0.5 + level / 2.0, dof)
    risk_j = energy if risk is None else energy + predictive_quantile(risk, dof) * sd
    return RemainingForecast(
        energy_j=energy, low_j=max(energy - z * sd, 0.0), high_j=energy + z * sd, level=level, risk_j=risk_j,
        risk=risk, model_energy_j=model_j, gain=gain, spread=spread, legs_remaining=int(p.size),
        legs_observed=n, soc=charge.soc, available_j=charge.available_j(), unseen_j=float(np.sum(unseen_j)), dof=dof,
    )
