"""The model-driven Monte Carlo mission: the route's energy drawn from the planning model's own predictive distribution.

Where the edge cost carries run-level standard deviations (a current model with an interval,
:mod:`planner.route_price`), one mission of :func:`planner.simulate_missions_mc` with
``draw_from="model"`` draws **one factor** ``z_g`` **per ground** the route crosses from that
ground's standardised predictive — standard normal where the model knows the ground, Student-t
with the ground's degrees of freedom where it never drove it
(:attr:`~planner.RouteEnergyInterval.dof_by_ground`) — and prices every edge on ground ``g`` at
``mean + z_g * sd``: the route energy is ``mean + sum_g z_g S_g`` (``S_g`` the linear sum of the
spreads on ``g``), the run-level error being shared by the whole run on one ground and
independent between grounds: the distribution of :class:`~planner.RouteEnergyInterval`, drawn
(on one ground, or grounds of one shape, exactly its quantiles; across grounds of different
degrees of freedom the interval's least is the conservative side). The standard normals are
drawn first, as for an all-Gaussian route; a Student-t factor is its normal divided by
``sqrt(chi2_dof / dof)`` (one chi-square draw per such ground, after them), so a route whose
grounds are all known draws exactly as before. The energy is drawn from the battery
at a constant power over the route's duration (:func:`energy.discharge_from_power`: internal
resistance and Peukert as for a driven mission) and checked against the reserve
(:func:`energy.energy_budget`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from energy import Battery, discharge_from_power, energy_budget

from ..route_price import RouteEnergyInterval
from .monte_carlo_result import failed_row, mission_row

__all__ = ["ModelMissionSetup", "MC_DRAW_MODES"]

#: What a Monte Carlo mission draws: the typed parameter ranges (a truth simulation per mission) or the model's distribution.
MC_DRAW_MODES = ("parameters", "model")


@dataclass(frozen=True)
class ModelMissionSetup:
    """Everything a model-driven Monte Carlo sample needs besides its seed.

    Attributes
    ----------
    forecast : RouteEnergyInterval
        The route's energy distribution on the planning cost.
    battery : Battery
        The nominal battery.
    duration_s : float
        Duration of the route (s), over which the energy is drawn at constant power.
    speed_mps : float
        The nominal speed (recorded per sample; not drawn).
    """

    forecast: RouteEnergyInterval
    battery: Battery
    duration_s: float
    speed_mps: float

    @property
    def ground_names(self) -> tuple[str, ...]:
        """Grounds with a spread on the route, in the order of the drawn factors."""
        return tuple(sorted(self.forecast.sd_by_ground_j))

    def drawn(self, seq: np.random.SeedSequence) -> tuple[float, ...]:
        """What one mission draws from its seed: the factors ``z_g``, then no payload and the nominal battery and
        speed (the row's drawn columns of :class:`MissionSetup.run`)."""
        rng = np.random.default_rng(seq)
        names = self.ground_names
        z = rng.standard_normal(len(names))
        dof = np.array([self.forecast.ground_dof(g) for g in names])
        heavy = np.isfinite(dof)
        if np.any(heavy):  # Student-t: a normal over the root of a chi-square by its degrees of freedom
            z[heavy] /= np.sqrt(rng.chisquare(dof[heavy]) / dof[heavy])
        return (*z.tolist(), 0.0, self.battery.capacity_ah, self.battery.internal_resistance_ohm, self.speed_mps)

    def run(self, seq: np.random.SeedSequence) -> tuple[tuple[float, ...], str]:
        """One mission: the factors ``z_g`` (:meth:`drawn`), then the row of :class:`MissionSetup.run`."""
        drawn = self.drawn(seq)
        names = self.ground_names
        z = np.array(drawn[:len(names)])
        spread = np.array([self.forecast.sd_by_ground_j[g] for g in names])
        energy_j = max(self.forecast.mean_j + float(np.dot(z, spread)), 0.0)
        power_w = energy_j / self.duration_s

        def drain() -> tuple[float, ...]:
            b = energy_budget(discharge_from_power(self.battery, [0.0, self.duration_s], [power_w, power_w]),
                              energy_j)
            return (float(b.actual_energy_j), float(b.actual_charge_mah), float(b.duration_s), float(b.arrival_soc),
                    float(b.arrival_soc), float(not b.feasible), float(b.depleted))

        return mission_row(drawn, drain)

    def run_chunk(self, seqs: list[np.random.SeedSequence]) -> list[tuple[tuple[float, ...], str]]:
        """:meth:`run` over several seeds (one dask task)."""
        return [self.run(q) for q in seqs]

    def failed_chunk(self, seqs: list[np.random.SeedSequence], exc: Exception) -> list[tuple[tuple[float, ...], str]]:
        """The rows of a task of :meth:`run_chunk` that failed with ``exc``: each mission's draws (:meth:`drawn`,
        here), its outcome NaN and ``exc`` its error (:func:`~planner.missions.monte_carlo_result.failed_row`)."""
        return [failed_row(self.drawn(q), exc) for q in seqs]
