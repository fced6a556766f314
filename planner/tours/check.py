"""The planned tours driven by the mission simulator, Monte Carlo: the share that ends above the reserve, beside Q."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from terrawatt_base.checks import check_int, check_seed
from terrawatt_base.errors import InvalidParameterError

from ..missions import MonteCarloResult, simulate_missions_mc
from .result import TourResult

__all__ = ["TourCheck", "simulate_tours_mc"]


@dataclass(frozen=True)
class TourCheck:
    """Each robot's tour driven ``n`` times.

    Attributes
    ----------
    risk : float
        The level the tours were planned at.
    runs : dict of str to MonteCarloResult
        Per robot (with a tour) its Monte Carlo study.
    draw_from : str
        ``"model"`` (the planning model's own distribution) or ``"parameters"`` (the truth simulator).
    """

    risk: float
    runs: dict[str, MonteCarloResult]
    draw_from: str

    @property
    def share_above_reserve(self) -> float:
        """The share of the robots' simulated tours that end above the reserve (over every robot's missions)."""
        done = [(1.0 - mc.p_below_reserve) * int(mc.completed.sum()) for mc in self.runs.values()]
        n = sum(int(mc.completed.sum()) for mc in self.runs.values())
        return sum(done) / n if n else float("nan")

    def summary(self) -> str:
        """One line per robot and the total, beside Q."""
        lines = [f"{name}: {100 * (1 - mc.p_below_reserve):.1f} % of {mc.n} tours end above the reserve"
                 for name, mc in self.runs.items()]
        lines.append(f"all: {100 * self.share_above_reserve:.1f} % above the reserve at Q = {self.risk:g} "
                     f"(draws from the {self.draw_from})")
        return "\n".join(lines)


def simulate_tours_mc(result: TourResult, n: int = 1000, *, seed: int | None = 0, draw_from: str | None = None,
                      workers: int | None = None, client: Any = None) -> TourCheck:
    """Drive each planned tour ``n`` times through :func:`planner.simulate_missions_mc`.

    With a cost that carries an interval the missions draw from the planning model's own
    distribution (``draw_from="model"``: one factor per ground per tour, the whole tour's
    energy, service included, as priced); otherwise the truth simulator drives the tour's
    route with drawn parameters (service energy not included).

    Raises
    ------
    InvalidParameterError
        Not a planned TourResult; ``n < 1``.
    """
    if not isinstance(result, TourResult) or result.cost is None:
        raise InvalidParameterError(f"result must be a TourResult from plan_tour, got {type(result).__name__!r}")
    n = check_int("n", n, low=1)
    seed = check_seed(seed)
    mode = draw_from or ("model" if result.cost.has_interval else "parameters")
    runs: dict[str, MonteCarloResult] = {}
    for k, tour in enumerate(result.tours):
        if not tour.legs:
            continue
        runs[tour.robot] = simulate_missions_mc(
            result.terrain, result.tour_route(k), tour.battery, n, seed=None if seed is None else seed + k,
            cost=result.cost, draw_from=mode, forecast=tour.energy if mode == "model" else None,
            workers=workers, client=client)
    return TourCheck(result.risk, runs, mode)
