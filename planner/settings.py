"""PlannerSettings: the tuning of every planner (OMPL planners, the lattice, any-angle, coarse-to-fine, the refinement)."""

from __future__ import annotations

from dataclasses import dataclass

from terrawatt_base.checks import check_int, check_real

__all__ = ["PlannerSettings"]


@dataclass(frozen=True)
class PlannerSettings:
    """Tuning of the planners (defaults measured on 512 x 512 procedural maps).

    Parameters
    ----------
    rewire_factor : float
        RRT*-family rewiring radius factor (> 0; OMPL's default is 1.1). Smaller values
        make fewer ``motionCost`` calls per iteration, hence more iterations per second.
    range_m : float or None
        Maximum motion length of the RRT* family (m, > 0); ``None`` keeps OMPL's default
        (20 % of the map diagonal).
    goal_bias : float
        Probability of sampling the goal in the RRT* family, in [0, 1].
    fmt_samples : int
        Number of samples of FMT* (>= 10); FMT* is a batch planner: its work is fixed by
        this (500 samples take ~0.4 s on a 512 x 512 map), and it returns ``timeout`` if the
        time limit or the work bound cuts it short.
    bit_samples_per_batch : int
        Samples per batch of BIT* (>= 1).
    lattice_stride_cells : int
        Node spacing (cells) of the lattice used by the ``"lattice"`` planner (>= 1; the
        reference optimum of ``Route.optimality_ratio`` always uses 1). Coarser lattices
        solve faster; the refinement then recovers most of the difference.
    anyangle_guide_stride_cells : int
        Node spacing (cells, >= 1) of the lattice whose route guides the ``"anyangle"``
        planner (:func:`planner.anyangle.anyangle_path`); a passage too narrow for it falls
        back to 1.
    anyangle_corridor_cells : int
        Half-width (cells, >= 1) of the corridor around the guide that the ``"anyangle"``
        planner's Theta* search may use.
    refine_max_steps : int
        Attempts of each OMPL refinement pass (``partialShortcutPath`` / ``perturbPath``), >= 1.
    refine_rounds : int
        Number of (shortcut, perturb) rounds (>= 1).
    coarse_factor : int
        Downsampling factor (>= 2) of the ``"coarse"`` planner (coarse-to-fine,
        :func:`planner.coarse.plan_coarse_to_fine`): its coarse lattice has ``factor**2``
        times fewer nodes.
    coarse_corridor_m : float or None
        Half-width (m, > 0) of the ``"coarse"`` planner's full-resolution corridor; ``None``:
        three coarse cells.

    Raises
    ------
    InvalidParameterError
        Any value out of range.
    """

    rewire_factor: float = 0.5
    range_m: float | None = None
    goal_bias: float = 0.05
    fmt_samples: int = 500
    bit_samples_per_batch: int = 200
    lattice_stride_cells: int = 1
    anyangle_guide_stride_cells: int = 2
    anyangle_corridor_cells: int = 12
    refine_max_steps: int = 300
    refine_rounds: int = 2
    coarse_factor: int = 4
    coarse_corridor_m: float | None = None

    def __post_init__(self) -> None:
        owner = "PlannerSettings"
        check_real("rewire_factor", self.rewire_factor, low=0.0, low_inclusive=False, owner=owner)
        if self.range_m is not None:
            check_real("range_m", self.range_m, low=0.0, low_inclusive=False, owner=owner)
        check_real("goal_bias", self.goal_bias, low=0.0, high=1.0, owner=owner)
        check_int("fmt_samples", self.fmt_samples, low=10, owner=owner)
        check_int("bit_samples_per_batch", self.bit_samples_per_batch, low=1, owner=owner)
        check_int("lattice_stride_cells", self.lattice_stride_cells, low=1, owner=owner)
        check_int("anyangle_guide_stride_cells", self.anyangle_guide_stride_cells, low=1, owner=owner)
        check_int("anyangle_corridor_cells", self.anyangle_corridor_cells, low=1, owner=owner)
        check_int("refine_max_steps", self.refine_max_steps, low=1, owner=owner)
        check_int("refine_rounds", self.refine_rounds, low=1, owner=owner)
        check_int("coarse_factor", self.coarse_factor, low=2, owner=owner)
        if self.coarse_corridor_m is not None:
            check_real("coarse_corridor_m", self.coarse_corridor_m, low=0.0, low_inclusive=False, owner=owner)
