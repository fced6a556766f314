"""EnergyModel: the one seam between energy and planning — energy per metre driven and per turn, per kind of cell.

Planning knows nothing else of energy. An edge cost (:class:`planner.EnergyCost`) tabulates
a model once per kind of cell the map holds — its *cell class* — over a grid of grades and
of heading changes, and prices every segment from those tables. What a cell class is
belongs to the model:

- :class:`energy.PhysicsEnergyModel`: the ground parameters of a ground
  (:class:`energy.GroundParams`) — the map's ground classes are its cell classes;
- :class:`planner.LearnedEnergyModel`: the id of a current model in a per-cell registry
  (:class:`planner.registry.CellModelRegistry`) — the cells that model serves are one class.

So ``ground`` always means a ground (its name, class id or parameters) in this library, and
the argument the protocol passes is called ``cell_class``. A model whose forecasts carry an
interval (:class:`IntervalEnergyModel`) also gives the run-level standard deviation of both,
which planning adds up along a route (:mod:`planner.route_price`).

The protocols are structural (:class:`typing.Protocol`, checkable at run time): any object
with these methods is an energy model, no base class is needed.

Examples
--------
>>> from energy import EnergyModel, PhysicsEnergyModel, robot_preset
>>> isinstance(PhysicsEnergyModel(robot_preset("husky")), EnergyModel)
True
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["EnergyModel", "IntervalEnergyModel"]


@runtime_checkable
class EnergyModel(Protocol):
    """What a planner asks of an energy model.

    Optionally, a ``robot`` attribute (:class:`energy.RobotParams`) gives the battery voltage
    and the turn rate an edge cost needs when they are not passed to it.
    """

    def energy_per_metre_j(self, speed_mps: float, grade: Any, cell_class: Any, /) -> np.ndarray:
        """Energy (J) per metre travelled at ``speed_mps`` on each of ``grade`` (rise / run) in ``cell_class``.

        ``+inf`` where a grade cannot be driven in that direction; never negative.
        """
        ...

    def turn_energy_j(self, heading_change_rad: Any, cell_class: Any, /) -> np.ndarray:
        """Energy (J) of turning in place by each of ``|heading_change_rad|`` in ``cell_class``."""
        ...


@runtime_checkable
class IntervalEnergyModel(EnergyModel, Protocol):
    """An :class:`EnergyModel` whose energies carry a run-level standard deviation.

    ``gives_interval`` says whether the spreads are there (a learned model without an
    interval may still have the methods).
    """

    gives_interval: bool

    def energy_per_metre_sd_j(self, speed_mps: float, grade: Any, cell_class: Any, /) -> np.ndarray:
        """Run-level standard deviation (J per metre travelled) of :meth:`energy_per_metre_j`."""
        ...

    def turn_energy_sd_j(self, heading_change_rad: Any, cell_class: Any, /) -> np.ndarray:
        """Run-level standard deviation (J) of :meth:`turn_energy_j`."""
        ...
