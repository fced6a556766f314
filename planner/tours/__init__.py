"""planner.tours — many sites on one charge (or a few, at charging points): which to visit, in what order, and what is
left when back (issue 33)."""

from __future__ import annotations

from .check import TourCheck, simulate_tours_mc
from .improve import DrivenPricer, ImproveOutcome, improve_tours
from .options import TourFleet, TourSearch
from .pricing import PairPrices, price_pairs
from .result import RobotTour, TourLeg, TourResult
from .sites import TourChargers, TourRobot, TourSites, read_tour_chargers_csv, read_tour_sites_csv
from .solver import TourPoints, TourProblem, solve_tours
from .tour import plan_tour, plan_tour_on_map

__all__ = [
    "plan_tour",
    "plan_tour_on_map",
    "TourResult",
    "TourSites",
    "TourRobot",
    "read_tour_sites_csv",
    "TourChargers",
    "read_tour_chargers_csv",
    "RobotTour",
    "TourLeg",
    "PairPrices",
    "price_pairs",
    "TourSearch",
    "TourFleet",
    "TourPoints",
    "TourProblem",
    "solve_tours",
    "improve_tours",
    "ImproveOutcome",
    "DrivenPricer",
    "simulate_tours_mc",
    "TourCheck",
]
