"""The energy OptimizationObjective: an OMPL motion costs its segment's drive energy (J), directed."""

from __future__ import annotations

import math

from ompl import base as ob

from ..kernels import CostArrays, walk_forward

__all__ = ["EnergyObjective"]


class EnergyObjective(ob.OptimizationObjective):
    """Minimise the drive energy (J) of a 2-D route over the compiled cell walk of a :class:`CostArrays`.

    ``motionCost(a, b)`` is the energy of the straight segment ``a -> b`` (``inf`` when it
    crosses a blocked cell or meets an undrivable grade); it is asymmetric, so
    :meth:`isSymmetric` is False (OMPL trap 1: RRT* would otherwise reuse the reverse
    direction's cost). ``motionCostHeuristic`` is the admissible
    ``min_energy_per_metre_j * |b - a|``. OMPL does not dispatch ``costToGo`` to Python
    overrides and ``setCostToGoHeuristic`` rejects Python callables, so informed planners see a
    zero cost-to-go (admissible, weak). Turn energies are not part of the objective (a 2-D
    state has no heading).

    Parameters
    ----------
    si : ompl.base.SpaceInformation
        The problem's space information.
    arrays : CostArrays
        The edge cost's packed arrays (``EnergyCost.arrays``).
    min_energy_per_metre_j : float
        Lowest energy per metre of any straight motion (``EnergyCost.min_energy_per_metre_j``).

    Attributes
    ----------
    evaluations : int
        ``motionCost`` calls so far (the work bound of a deterministic solve counts these).
    """

    def __init__(self, si: ob.SpaceInformation, arrays: CostArrays, min_energy_per_metre_j: float) -> None:
        super().__init__(si)
        self._cells = arrays.cells
        self._table = arrays.grade_table
        self._geo = arrays.geo
        self._per_m = float(min_energy_per_metre_j)
        self.evaluations = 0

    def motionCost(self, a, b):  # noqa: N802 - OMPL API
        self.evaluations += 1
        return ob.Cost(walk_forward(self._cells, self._table, self._geo, a[0], a[1], b[0], b[1]))

    def stateCost(self, s):  # noqa: N802 - OMPL API
        return ob.Cost(0.0)

    def isSymmetric(self):  # noqa: N802 - OMPL API
        return False

    def motionCostHeuristic(self, a, b):  # noqa: N802 - OMPL API
        return ob.Cost(self._per_m * math.hypot(b[0] - a[0], b[1] - a[1]))
