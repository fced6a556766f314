"""A route's energy distribution and the risk levels read from it (the math of intervals and risk-aware costs).

A cost priced by a model with a predictive interval (:class:`~planner.LearnedEnergyModel`
over a model whose ``gives_interval`` is True) carries, beside its mean tables, the
**run-level** standard deviation of every table entry (:attr:`planner.EnergyCost.grade_sd_table_j_per_m`,
:attr:`planner.EnergyCost.turn_sd_table_j`). That spread is the part of the model's error shared by a
whole run on one ground (what the model does not know about the ground, how one run differs
from another), so along a route it does not average out:

- the route's **mean** energy is the sum of its edge means (:meth:`planner.EnergyCost.path_energy_j`);
- **within one ground** (one table row) the edge spreads add **linearly**;
- the per-ground sums, grounds being independent of each other, combine by the **root of the
  sum of squares** (:func:`energy.models.forecast.combine_ground_sds`).

**Shape.** Each row's spreads are the scale of the model's predictive on that ground
(:attr:`planner.EnergyCost.spread_dof`): a Gaussian (``dof = inf``) where the model knows the ground, a
**Student-t** with as many degrees of freedom as grounds taught the new-ground spread where it
never drove it (:mod:`energy.models.forecast`). The same predictive gives every interval the
planner reports: :class:`RouteEnergyInterval` (P50, P90, central intervals) takes the route's
energy as a Student-t with the **least** degrees of freedom of the grounds it crosses with a
spread (a Gaussian when all are known); the Monte Carlo missions draw each ground's factor from
its own predictive (:mod:`planner.missions.monte_carlo_model`); the navigator's forecast of what
remains uses the same quantile (:mod:`planner.missions.remaining`).

**Risk-aware planning.** :meth:`planner.CostTables.at_quantile` gives the tables
``mean + z_Q * sd`` per entry, ``z_Q`` the ``Q`` quantile of the row's standardised predictive
(:func:`energy.models.forecast.predictive_quantile` with the row's degrees of freedom: the
standard normal's on a known ground), floored at 0 (an edge never pays back energy). A planner
minimising a cost on them minimises

``sum over edges (mean_e + z_Q,g(e) sd_e) = mean_route + sum over grounds z_Q,g S_g``

with ``S_g`` the linear sum of spreads on ground ``g``. On a route over **one ground** that is
exactly the route's ``Q`` quantile (its sd is ``S_g``, its degrees of freedom those of ``g``).
On a route over several independent grounds the route's sd is ``sqrt(sum S_g**2) <= sum S_g``:
for ``Q > 0.5`` the objective is an **upper bound** of the route's ``Q`` quantile
(conservative: it penalises crossing many uncertain grounds a little more than their
independence warrants), for ``Q < 0.5`` a lower bound. The objective is still additive over
edges, which the lattice and the OMPL objective need; the route that is finally reported is
priced exactly (:func:`planner.price_route`: a :class:`RouteEnergyInterval`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from energy.models.forecast import check_dof, predictive_quantile
from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

__all__ = ["RouteEnergyInterval", "check_risk_level", "check_planning_risk", "INTERVAL_LEVEL"]

#: Central interval reported beside P50 / P90 (0.8: P10-P90).
INTERVAL_LEVEL = 0.8


def check_risk_level(q: Any, name: str = "q") -> float:
    """A risk level ``Q`` checked: a number in the open interval (0, 1).

    Raises
    ------
    InvalidParameterError
        Not a number, or outside (0, 1); the message names ``name``.
    """
    return check_real(name, q, low=0.0, high=1.0, low_inclusive=False, high_inclusive=False)


def check_planning_risk(q: Any, name: str = "risk") -> float:
    """A risk level to plan or decide on: a number in [0.5, 1).

    Planning on a quantile below the median plans on luck: ``--risk 1e-9`` priced every edge at
    mean - 6 sd, floored at 0, and reported a route "costing" 0 J. :meth:`planner.CostTables.at_quantile` and
    :meth:`RouteEnergyInterval.quantile_j` still take any level in (0, 1) (a P10 is a fine thing to
    report); what a route is chosen or a mission is judged on is at least the median.

    Raises
    ------
    InvalidParameterError
        Not a number, outside (0, 1), or below 0.5; the message names ``name``.

    Examples
    --------
    >>> check_planning_risk(0.9)
    0.9
    >>> check_planning_risk(0.1, "--risk")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: --risk 0.1 lies below the median: ...
    """
    q = check_risk_level(q, name)
    if q < 0.5:
        raise InvalidParameterError(
            f"{name} {q:g} lies below the median: planning on it assumes the energy comes out lower than it does in "
            f"{100 * (1 - q):.4g} % of runs; give a level in [0.5, 1), e.g. 0.9 (0.5 plans on the mean)", parameter=name)
    return q


@dataclass(frozen=True)
class RouteEnergyInterval:
    """The distribution of a route's battery energy under a model with an interval: a mean, a scale and a tail.

    Attributes
    ----------
    mean_j : float
        Mean energy (J): the sum of the edge means (turns included).
    sd_j : float
        Standard deviation (J): per ground the edge spreads summed linearly, the grounds
        combined by root-sum-of-squares.
    sd_by_ground_j : dict of str to float
        The linear per-ground sums (J), keyed by the cost's row labels (grounds the route
        does not cross are left out).
    dof : float
        Degrees of freedom of the Student-t the quantiles are read from (``inf``, the
        default: Gaussian): the least of the grounds the route crosses with a non-zero spread.
        A sum of independent Student-t's with other degrees of freedom has no closed form;
        the least is **conservative** (its tails are the heaviest of the parts'), exact on a
        route over one ground or over grounds that share one value.
    dof_by_ground : dict of str to float
        Each crossed ground's own degrees of freedom (keys of ``sd_by_ground_j``; a ground
        left out has ``dof``): what a Monte Carlo draw of the route draws per ground.

    Raises
    ------
    InvalidParameterError
        A negative or non-finite mean or spread, degrees of freedom not > 0.

    Examples
    --------
    >>> iv = RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0})
    >>> round(iv.p90_j, 1), [round(x, 1) for x in iv.interval_j(0.8)]
    (1128.2, [871.8, 1128.2])
    >>> round(RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0}, dof=3.0).p90_j, 1)  # a ground never driven
    1163.8
    """

    mean_j: float
    sd_j: float
    sd_by_ground_j: dict[str, float]
    dof: float = math.inf
    dof_by_ground: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("mean_j", "sd_j"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value >= 0):
                raise InvalidParameterError(f"RouteEnergyInterval.{name} must be a finite energy >= 0, got {value!r}")
            object.__setattr__(self, name, value)
        by = {str(k): float(v) for k, v in dict(self.sd_by_ground_j).items()}
        if any(not (math.isfinite(v) and v >= 0) for v in by.values()):
            raise InvalidParameterError(f"RouteEnergyInterval.sd_by_ground_j must hold finite spreads >= 0, got {by!r}")
        object.__setattr__(self, "sd_by_ground_j", by)
        object.__setattr__(self, "dof", check_dof(self.dof, "RouteEnergyInterval.dof"))
        dofs = {str(k): check_dof(v, "RouteEnergyInterval.dof_by_ground") for k, v in dict(self.dof_by_ground).items()}
        if set(dofs) - set(by):
            raise InvalidParameterError(f"RouteEnergyInterval.dof_by_ground names grounds without a spread: "
                                        f"{sorted(set(dofs) - set(by))!r}")
        object.__setattr__(self, "dof_by_ground", dofs)

    def ground_dof(self, ground: str) -> float:
        """The degrees of freedom of ``ground``'s factor (its own, else the route's :attr:`dof`)."""
        return self.dof_by_ground.get(str(ground), self.dof)

    def quantile_j(self, q: float) -> float:
        """The ``q`` quantile of the route energy (J), ``q`` in (0, 1): ``mean + predictive_quantile(q, dof) * sd``."""
        return self.mean_j + predictive_quantile(check_risk_level(q), self.dof) * self.sd_j

    @property
    def p50_j(self) -> float:
        """Median energy (J); the mean, the distribution (Gaussian or Student-t) being symmetric."""
        return self.mean_j

    @property
    def p90_j(self) -> float:
        """90th percentile of the energy (J)."""
        return self.quantile_j(0.9)

    def interval_j(self, level: float = INTERVAL_LEVEL) -> tuple[float, float]:
        """Central ``level`` interval of the energy (J), e.g. 0.8: (P10, P90)."""
        lv = check_risk_level(level, "level")
        return self.quantile_j(0.5 - lv / 2.0), self.quantile_j(0.5 + lv / 2.0)

    def to_dict(self) -> dict[str, Any]:
        """The block route.json holds under ``energy_interval`` (J and Wh, units in the keys)."""
        lo, hi = self.interval_j(INTERVAL_LEVEL)
        shape = "gaussian" if math.isinf(self.dof) else f"student-t with {self.dof:g} degrees of freedom"
        out = {
            "distribution": f"{shape}: per ground the run-level spreads add linearly, grounds independent",
            "mean_j": self.mean_j,
            "sd_j": self.sd_j,
            "p50_j": self.p50_j,
            "p90_j": self.p90_j,
            "central_level": INTERVAL_LEVEL,
            "central_interval_j": [lo, hi],
            "mean_wh": self.mean_j / 3600.0,
            "p50_wh": self.p50_j / 3600.0,
            "p90_wh": self.p90_j / 3600.0,
            "central_interval_wh": [lo / 3600.0, hi / 3600.0],
            "sd_by_ground_j": dict(self.sd_by_ground_j),
        }
        if not math.isinf(self.dof):  # a Gaussian's block stays as it was
            out["dof"] = self.dof
            out["dof_by_ground"] = {g: (d if math.isfinite(d) else None) for g, d in self.dof_by_ground.items()}
        return out
