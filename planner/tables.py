"""Energy tables of an edge cost: the one grade/turn table builder, ground-to-row mapping, checks.

An :class:`~planner.EnergyCost` prices a cell by a *table row*: the energy per horizontal
metre at grades uniformly spaced over ``[-tan(max_slope), +tan(max_slope)]`` and the energy
of turning in place at angles uniformly spaced over ``[0, pi]``. :func:`tabulate` builds
those rows from any energy model (the physics model per ground, the learned model per model
id): it is the only place tables are computed. :meth:`CostTables.at_quantile` prices every
entry at a quantile of its predictive (what a risk level plans on).

**Stop-turn-go.** The robot drives a route stop-turn-go (:mod:`energy.profiles`): it stops at
every waypoint where it turns, pivots with a ramped yaw rate and drives the next segment from
rest; it starts the route from rest and ends it at rest. The grade table prices steady driving
at the planning speed; what the stops and starts add is in the turn table: with
``stop_turn_go_rate_radps`` (the physics model, :meth:`planner.CostSpec.build`), entry ``j`` of a
row is the energy of the pivot by ``angles[j]`` on its profile (:func:`energy.profiles.pivot_commands`)
plus one **stop-and-go** (a rest-to-rest straight less the same length at the steady energy
per metre), both priced by the model itself on level ground (:func:`stop_turn_go_rows`). Column 0
(angle 0) is then the stop-and-go alone: what a route pays once for starting from rest and
stopping at rest (:meth:`planner.EnergyCost.turn_energies_j`, half at each end). A waypoint the
robot drives through (a heading change of at most :data:`energy.profiles.COLLINEAR_TOL_RAD`)
pays nothing. Tables without it (column 0 at 0: a learned model's, tables given directly) price
no stop and go.

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
priced exactly (:func:`planner.price_route`: a :class:`~planner.route_price.RouteEnergyInterval`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from energy import EnergyModel, IntervalEnergyModel, PhysicsEnergyModel
from energy.models.forecast import check_dof, predictive_quantile
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2, pivot_commands, waypoint_commands
from terrain.terrain_map import UNKNOWN_GROUND, TerrainMap
from terrawatt_base.checks import check_int, check_real
from terrawatt_base.errors import GridMismatchError, InvalidParameterError, UnknownNameError

__all__ = [
    "DEFAULT_GRADE_SAMPLES",
    "DEFAULT_TURN_SAMPLES",
    "grade_grid",
    "turn_grid",
    "check_table_sizes",
    "tabulate",
    "stop_turn_go_rows",
    "ground_table_rows",
    "CostTables",
    "check_spread_tables",
    "check_spread_dof",
    "check_risk_level",
    "check_planning_risk",
]

#: Default number of samples of each ground's energy-per-metre-vs-grade table (odd: grade 0 is a sample).
DEFAULT_GRADE_SAMPLES = 513
#: Default number of samples of each ground's turn-energy-vs-angle table over [0, pi].
DEFAULT_TURN_SAMPLES = 65
#: Sampling period (s) of the profiles the stop-turn-go turn tables are priced on (their sampling error is
#: below 0.3 J an entry).
STOP_GO_DT_S = 0.005


def check_table_sizes(grade_samples: Any, turn_samples: Any) -> tuple[int, int]:
    """``(grade_samples, turn_samples)`` checked: an odd integer >= 3 and an integer >= 2.

    Raises
    ------
    InvalidParameterError
        Not integers, or out of range.
    """
    n_grade = check_int("grade_samples", grade_samples, low=3)
    if n_grade % 2 == 0:
        raise InvalidParameterError(f"grade_samples must be an odd integer >= 3, got {grade_samples!r}")
    return n_grade, check_int("turn_samples", turn_samples, low=2)


def grade_grid(max_slope_rad: float, grade_samples: int) -> np.ndarray:
    """The uniform grade grid ``[-tan(max_slope_rad), +tan(max_slope_rad)]`` of ``grade_samples`` points."""
    grade_max = math.tan(float(max_slope_rad))
    return np.linspace(-grade_max, grade_max, int(grade_samples))


def turn_grid(turn_samples: int) -> np.ndarray:
    """The uniform heading-change grid ``[0, pi]`` of ``turn_samples`` points."""
    return np.linspace(0.0, math.pi, int(turn_samples))


def tabulate(
    model: EnergyModel | IntervalEnergyModel,
    speed_mps: float,
    cell_classes: Sequence[Any],
    labels: Sequence[str],
    *,
    max_slope_rad: float,
    grade_samples: int,
    turn_samples: int,
    spread: bool = False,
    stop_turn_go_rate_radps: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Grade and turn tables of an energy model, one row per ground (the one table builder).

    Row ``i`` holds ``model.energy_per_metre_j(speed_mps, grades, cell_classes[i])`` (J per metre
    *travelled*) times ``sqrt(1 + grade**2)`` (J per *horizontal* map metre) on
    :func:`grade_grid`, and ``model.turn_energy_j(angles, cell_classes[i])`` on :func:`turn_grid`
    (with ``stop_turn_go_rate_radps``: :func:`stop_turn_go_rows`, the stop, pivot and start of the
    stop-turn-go drive).

    Parameters
    ----------
    model : energy.EnergyModel
        ``energy_per_metre_j(speed, grades, cell_class)`` and ``turn_energy_j(angles,
        cell_class)`` (the physics model, a learned model); with ``spread``, an
        :class:`energy.IntervalEnergyModel`.
    speed_mps : float
        Planning speed (m/s).
    cell_classes : sequence
        The model's cell class of each row (ground parameters for the physics model, model
        ids for a learned one).
    labels : sequence of str
        A name per row, for messages.
    max_slope_rad, grade_samples, turn_samples
        The grade grid and the turn grid.
    spread : bool
        Tabulate the run-level standard deviation instead of the mean, from
        ``model.energy_per_metre_sd_j`` / ``model.turn_energy_sd_j`` (a model with an
        interval; see :mod:`planner.route_price` for how a route adds the spreads up).
    stop_turn_go_rate_radps : float, optional
        Price the turn table as the stop-turn-go drive pivots at this yaw rate (rad/s; the
        cost's turn rate): a model with ``energy_j`` over a sampled motion (the physics model).
        Not with ``spread``.

    Returns
    -------
    grade_table, turn_table : ndarray, shape (len(cell_classes), grade_samples) and (len(cell_classes), turn_samples)

    Raises
    ------
    InvalidParameterError
        The model returned arrays of other shapes; ``stop_turn_go_rate_radps`` with ``spread``.
    """
    grades, angles = grade_grid(max_slope_rad, grade_samples), turn_grid(turn_samples)
    if spread:
        if stop_turn_go_rate_radps is not None:
            raise InvalidParameterError("stop_turn_go_rate_radps prices the mean turn table; not with spread=True",
                                        parameter="stop_turn_go_rate_radps")
        return _table_rows(model.energy_per_metre_sd_j, model.turn_energy_sd_j, speed_mps, cell_classes, labels,
                           grades, angles, "spread ")
    grade_table, turn_table = _table_rows(model.energy_per_metre_j, model.turn_energy_j, speed_mps, cell_classes,
                                          labels, grades, angles, "")
    if stop_turn_go_rate_radps is not None:
        turn_table = stop_turn_go_rows(model, speed_mps, cell_classes, turn_samples=turn_samples,
                                       turn_rate_radps=stop_turn_go_rate_radps)
    return grade_table, turn_table


def stop_turn_go_rows(model: Any, speed_mps: float, cell_classes: Sequence[Any], *, turn_samples: int,
                      turn_rate_radps: float, accel_mps2: float = DEFAULT_ACCEL_MPS2,
                      yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2) -> np.ndarray:
    """Turn table of the stop-turn-go drive, one row per ground: stop, pivot by each angle of :func:`turn_grid`, go.

    Entry ``j`` of row ``i`` is ``model.energy_j`` of the pivot by ``angles[j]``
    (:func:`energy.profiles.pivot_commands`: the yaw rate ramped up and down) plus the row's
    stop-and-go: ``model.energy_j`` of one rest-to-rest straight of ``2 speed**2 / accel``
    metres (:func:`energy.profiles.waypoint_commands`) less that length at
    ``model.energy_per_metre_j(speed_mps, 0)``: the ramps' extra seconds at the electronics'
    power, the kinetic energy never recovered, the control board's start-up. Column 0 is the
    stop-and-go alone. The profiles are those a mission drives and
    :func:`planner.price_route` (``how="profile"``) prices, on level ground, sampled every
    :data:`STOP_GO_DT_S`; the same model prices them, so nothing here is a second formula. A
    segment shorter than ``speed**2 / accel`` (which never reaches the cruise speed) stops and
    starts for a little less.

    Parameters
    ----------
    model : energy.PhysicsEnergyModel
        ``energy_j(time_s, speed_mps, omega_radps, ground)`` and ``energy_per_metre_j``.
    speed_mps : float
        Planning speed (m/s).
    cell_classes : sequence
        The model's ground of each row.
    turn_samples : int
        Samples of :func:`turn_grid`.
    turn_rate_radps, accel_mps2, yaw_accel_radps2 : float
        The profile's pivot rate (rad/s), acceleration (m/s^2) and yaw acceleration (rad/s^2).

    Returns
    -------
    ndarray, shape (len(cell_classes), turn_samples)

    Raises
    ------
    InvalidParameterError
        A model without ``energy_j``; bad rates.

    Examples
    --------
    >>> from energy import PhysicsEnergyModel, ground_preset, robot_preset
    >>> row = stop_turn_go_rows(PhysicsEnergyModel(robot_preset("husky")), 0.5, [ground_preset("asphalt")],
    ...                         turn_samples=3, turn_rate_radps=0.5)[0]
    >>> bool(40.0 < row[0] < 80.0), bool(row[2] > row[1] > row[0])  # the stop-and-go alone, then a pivot more
    (True, True)
    """
    if not callable(getattr(model, "energy_j", None)):
        raise InvalidParameterError(f"stop-turn-go tables need a model that prices a sampled motion (energy_j), "
                                    f"got {type(model).__name__!r}", parameter="model")
    figures = (float(speed_mps), float(turn_rate_radps), float(accel_mps2), float(yaw_accel_radps2), int(turn_samples))
    rows = []
    for ground in cell_classes:
        if type(model) is PhysicsEnergyModel:  # a pure function of hashable values: priced once per process
            rows.append(_physics_row(model.robot, model.effects, ground, *figures))
        else:
            rows.append(_stop_turn_go_row(model, ground, *figures))
    return np.array(rows, dtype=np.float64).reshape(len(cell_classes), int(turn_samples))


@functools.lru_cache(maxsize=256)
def _physics_row(robot: Any, effects: tuple[str, ...], ground: Any, *figures: Any) -> np.ndarray:
    return _stop_turn_go_row(PhysicsEnergyModel(robot, effects), ground, *figures)


def _stop_turn_go_row(model: Any, ground: Any, speed_mps: float, turn_rate_radps: float, accel_mps2: float,
                      yaw_accel_radps2: float, turn_samples: int) -> np.ndarray:
    """One row of :func:`stop_turn_go_rows`: the stop-and-go, then the pivot by each angle plus it."""
    length = 2.0 * speed_mps**2 / accel_mps2
    p = waypoint_commands([[0.0, 0.0], [length, 0.0]], speed_mps, accel_mps2=accel_mps2, dt_s=STOP_GO_DT_S)
    stop_go = (model.energy_j(p.time_s, p.v_mps, p.omega_radps, ground)
               - length * float(model.energy_per_metre_j(speed_mps, 0.0, ground)))
    out = np.full(turn_samples, stop_go)
    for j, angle in enumerate(turn_grid(turn_samples)[1:], start=1):
        p = pivot_commands(angle, turn_rate_radps=turn_rate_radps, yaw_accel_radps2=yaw_accel_radps2,
                           dt_s=STOP_GO_DT_S)
        out[j] += model.energy_j(p.time_s, p.v_mps, p.omega_radps, ground)
    out.setflags(write=False)
    return out


def _table_rows(per_metre: Any, per_turn: Any, speed_mps: float, cell_classes: Sequence[Any], labels: Sequence[str],
                grades: np.ndarray, angles: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``per_metre(speed, grades, c) * sqrt(1 + grade**2)`` and ``per_turn(angles, c)`` per cell class ``c``."""
    horizontal = np.sqrt(1.0 + grades**2)
    grade_table = np.empty((len(cell_classes), grades.size))
    turn_table = np.empty((len(cell_classes), angles.size))
    for i, cell_class in enumerate(cell_classes):
        e = np.asarray(per_metre(speed_mps, grades, cell_class), dtype=np.float64)
        te = np.asarray(per_turn(angles, cell_class), dtype=np.float64)
        if e.shape != grades.shape or te.shape != angles.shape:
            raise InvalidParameterError(
                f"model returned {what}shapes {e.shape!r} / {te.shape!r} for {grades.shape!r} grades / "
                f"{angles.shape!r} angles on {labels[i]!r}; expected the input shapes"
            )
        grade_table[i] = e * horizontal
        turn_table[i] = te
    return grade_table, turn_table


def check_spread_tables(
    grade_table: np.ndarray, turn_table: np.ndarray, grade_sd_table: Any, turn_sd_table: Any
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Validated read-only copies of an edge cost's standard-deviation tables (both or neither).

    Parameters
    ----------
    grade_table, turn_table : ndarray
        The checked mean tables (:class:`CostTables`); the spreads must have their shapes.
    grade_sd_table, turn_sd_table : array_like or None
        Run-level standard deviations (J per horizontal metre, J), finite and >= 0.

    Returns
    -------
    (grade_sd, turn_sd) : ndarray or None

    Raises
    ------
    InvalidParameterError
        Only one of the two given, other shapes, negative or non-finite values.
    """
    if grade_sd_table is None and turn_sd_table is None:
        return None, None
    if grade_sd_table is None or turn_sd_table is None:
        raise InvalidParameterError("grade_sd_table_j_per_m and turn_sd_table_j go together: give both or neither")
    out = []
    for name, value, like in (("grade_sd_table_j_per_m", grade_sd_table, grade_table),
                              ("turn_sd_table_j", turn_sd_table, turn_table)):
        try:
            arr = np.array(value, dtype=np.float64, order="C", copy=True)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"{name} must be an array of numbers: {exc}") from exc
        if arr.shape != like.shape:
            raise InvalidParameterError(f"{name} must have the shape of its mean table {like.shape!r}, got {arr.shape!r}")
        if not np.all(np.isfinite(arr)) or np.any(arr < 0):
            raise InvalidParameterError(f"{name} must hold finite standard deviations >= 0")
        arr.setflags(write=False)
        out.append(arr)
    return out[0], out[1]


def check_spread_dof(spread_dof: Any, n_rows: int, has_spreads: bool) -> tuple[float, ...]:
    """Validated degrees of freedom of an edge cost's spread tables, one per table row (``inf``: Gaussian).

    Parameters
    ----------
    spread_dof : sequence of float or None
        Per table row, the degrees of freedom of the Student-t the row's spreads are the
        scale of (> 0; ``inf`` for a Gaussian); None: every row Gaussian.
    n_rows : int
        Number of table rows.
    has_spreads : bool
        Whether the cost carries spread tables (degrees of freedom without them are refused).

    Returns
    -------
    tuple of float
        ``n_rows`` values (all ``inf`` for None).

    Raises
    ------
    InvalidParameterError
        Another length, a value not > 0, degrees of freedom without spread tables.
    """
    if spread_dof is None:
        return (math.inf,) * n_rows
    if not has_spreads:
        raise InvalidParameterError("spread_dof goes with grade_sd_table_j_per_m and turn_sd_table_j: give them too")
    try:
        values = tuple(check_dof(d, "spread_dof") for d in spread_dof)
    except TypeError as exc:
        raise InvalidParameterError(f"spread_dof must be a sequence of numbers, got {spread_dof!r:.80}") from exc
    if len(values) != n_rows:
        raise InvalidParameterError(f"spread_dof must hold one value per table row ({n_rows}), got {len(values)}")
    return values


def ground_table_rows(
    terrain: TerrainMap, grounds: Mapping[str, Any] | Mapping[int, Any], unknown_ground: Any = None
) -> tuple[np.ndarray, list[Any], list[str]]:
    """Map a map's ground classes onto table rows: ``(rows per cell, params per row, label per row)``.

    ``grounds`` is keyed by class name (``terrain.ground_names``) or class id; only classes
    present in the map get a row. Unknown cells (class ``-1``) use ``unknown_ground``.

    Raises
    ------
    UnknownNameError
        A class of the map without parameters.
    InvalidParameterError
        Unknown-ground cells without ``unknown_ground``; keys that are neither names nor ids.
    """
    names = terrain.ground_names
    by_id: dict[int, Any] = {}
    for key, params in dict(grounds).items():
        if isinstance(key, str):
            for gid, gname in names.items():
                if gname == key:
                    by_id[gid] = params
        elif isinstance(key, (int, np.integer)) and not isinstance(key, bool):
            by_id[int(key)] = params
        else:
            raise InvalidParameterError(f"grounds keys must be ground names or class ids, got {key!r}")
    ground = np.asarray(terrain.ground)
    present = [int(v) for v in np.unique(ground)]
    params_rows: list[Any] = []
    labels: list[str] = []
    lut = np.full(int(max(present + [0])) + 2, -1, dtype=np.int32)  # lut[gid + 1] -> row
    for gid in present:
        if gid == UNKNOWN_GROUND:
            if unknown_ground is None:
                n_unknown = int(np.count_nonzero(ground == UNKNOWN_GROUND))
                raise InvalidParameterError(
                    f"the map has {n_unknown} cells of unknown ground ({UNKNOWN_GROUND}) and "
                    "unknown_ground is None; pass unknown_ground=<ground params> for them"
                )
            params = unknown_ground
            label = "unknown"
        else:
            if gid not in by_id:
                label = names.get(gid, str(gid))
                raise UnknownNameError(
                    f"ground class {label!r} (id {gid}) of the map has no parameters in grounds; "
                    f"grounds has {sorted(map(str, dict(grounds)))!r}"
                )
            params = by_id[gid]
            label = names.get(gid, str(gid))
        lut[gid + 1] = len(params_rows)
        params_rows.append(params)
        labels.append(label)
    return lut[ground.astype(np.int64) + 1], params_rows, labels


@dataclass(frozen=True, eq=False)
class CostTables:
    """The energy tables of an edge cost, one row per kind of cell: a straight metre at each grade and a turn at each angle.

    Checked when made, and read-only copies of what was given; an :class:`~planner.EnergyCost`
    lays them over a map (a row per cell), :meth:`~planner.EnergyCost.with_tables` swaps them
    (the replan after a model update).

    Parameters
    ----------
    grade_table_j_per_m : array_like, shape (n_rows, n_grade)
        Energy per horizontal metre (J/m, >= 0; ``+inf`` = this grade cannot be driven on
        this row's ground) at uniformly spaced grades from ``-tan(max_slope_rad)`` to
        ``+tan(max_slope_rad)``; ``n_grade`` odd and >= 3.
    turn_table_j : array_like, shape (n_rows, n_turn)
        Energy (J, >= 0, finite) of turning in place by angles uniformly spaced over ``[0, pi]``,
        the stop before and the start after included where the tables price the stop-turn-go
        drive (the module docstring); column 0 is then the stop-and-go alone, which a route pays
        once (its start and its end), else 0.
    ground_labels : sequence of str, optional
        A label per row (ground names), for messages; default ``row0``, ``row1``, ...
    grade_sd_table_j_per_m, turn_sd_table_j : array_like, optional
        Run-level standard deviations of the two tables (same shapes, finite, >= 0), from a
        model with a predictive interval; both or neither. No query of the cost reads them:
        a route's interval (:func:`planner.price_route`) and :meth:`at_quantile` do.
    spread_dof : sequence of float, optional
        Per row, the degrees of freedom of the distribution the row's spreads are the scale of:
        ``inf`` for a Gaussian, finite for a Student-t (as many as grounds on a ground the model never
        drove, as runs on one it drove: :attr:`energy.models.forecast.CurrentForecast.dof`). Default: every row ``inf``; only
        with the spread tables.

    Raises
    ------
    InvalidParameterError
        Tables of the wrong shape or with negative / NaN energies (or infinite turn
        energies); labels of the wrong length; spreads alone, of other shapes, negative or
        non-finite; degrees of freedom of another length, not > 0, or without spreads.

    Examples
    --------
    >>> tables = CostTables([[20.0, 10.0, 30.0]], [[0.0, 5.0]], ground_labels=("asphalt",))
    >>> tables.n_rows, tables.spread_dof, tables.grade_table_j_per_m.flags.writeable
    (1, (inf,), False)
    """

    grade_table_j_per_m: np.ndarray
    turn_table_j: np.ndarray
    ground_labels: tuple[str, ...] | None = None
    grade_sd_table_j_per_m: np.ndarray | None = None
    turn_sd_table_j: np.ndarray | None = None
    spread_dof: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        grade, turn, labels = _check_mean_tables(self.grade_table_j_per_m, self.turn_table_j, self.ground_labels)
        set_(self, "grade_table_j_per_m", grade)
        set_(self, "turn_table_j", turn)
        set_(self, "ground_labels", labels)
        grade_sd, turn_sd = check_spread_tables(grade, turn, self.grade_sd_table_j_per_m, self.turn_sd_table_j)
        set_(self, "grade_sd_table_j_per_m", grade_sd)
        set_(self, "turn_sd_table_j", turn_sd)
        set_(self, "spread_dof", check_spread_dof(self.spread_dof, grade.shape[0], grade_sd is not None))

    @property
    def n_rows(self) -> int:
        """Number of rows (kinds of cell)."""
        return int(self.grade_table_j_per_m.shape[0])

    def at_quantile(self, q: float) -> CostTables:
        """These tables with every entry at its ``q`` quantile, ``mean + z_q * sd`` floored at 0; the spreads kept.

        ``z_q`` is read per row from the row's predictive
        (:func:`~energy.models.forecast.predictive_quantile` with the row's :attr:`spread_dof`): the
        standard normal's on a ground the model knows, a Student-t's on one it never drove. A cost
        on these tables (:meth:`planner.EnergyCost.with_tables`) is what a risk level plans on:
        exactly a route's ``q`` quantile on one ground, an upper bound of it across independent
        grounds for ``q > 0.5`` (the module docstring).

        Parameters
        ----------
        q : float
            Risk level in (0, 1); 0.5 gives the mean tables.

        Returns
        -------
        CostTables

        Raises
        ------
        InvalidParameterError
            ``q`` outside (0, 1); tables without spreads.

        Examples
        --------
        >>> tables = CostTables([[20.0, 10.0, 30.0]], [[0.0, 5.0]], grade_sd_table_j_per_m=[[2.0, 2.0, 2.0]],
        ...                     turn_sd_table_j=[[0.0, 1.0]])
        >>> [round(float(x), 2) for x in tables.at_quantile(0.9).grade_table_j_per_m[0]]
        [22.56, 12.56, 32.56]
        """
        q = check_risk_level(q)
        if self.grade_sd_table_j_per_m is None:
            raise InvalidParameterError(
                "these tables carry no standard deviations: their energy model gives no interval (price the map "
                "with a current model whose gives_interval is True)", parameter="tables")
        z = np.array([predictive_quantile(q, dof) for dof in self.spread_dof])[:, None]  # per row
        grade = np.maximum(self.grade_table_j_per_m + z * self.grade_sd_table_j_per_m, 0.0)
        turn = np.maximum(self.turn_table_j + z * self.turn_sd_table_j, 0.0)
        return dataclasses.replace(self, grade_table_j_per_m=grade, turn_table_j=turn)

    def rows_on(self, shape: tuple[int, int], ground_rows: Any) -> np.ndarray:
        """``ground_rows`` checked as this table's rows of a map of ``shape``: a read-only int32 copy.

        Raises
        ------
        GridMismatchError
            ``ground_rows`` not of ``shape``.
        InvalidParameterError
            Values that are not rows of these tables.
        """
        rows = np.asarray(ground_rows)
        if rows.shape != tuple(shape):
            raise GridMismatchError(f"ground_rows has shape {rows.shape!r}; the map's grid is {tuple(shape)!r}")
        n_rows = self.n_rows
        if not np.issubdtype(rows.dtype, np.integer) or rows.min() < 0 or rows.max() >= n_rows:
            raise InvalidParameterError(
                f"ground_rows must hold integer table rows in 0..{n_rows - 1}, got values in "
                f"[{rows.min()!r}, {rows.max()!r}] of dtype {rows.dtype}"
            )
        out = rows.astype(np.int32)
        out.setflags(write=False)
        return out


def _check_mean_tables(grade_table_j_per_m: Any, turn_table_j: Any,
                       ground_labels: Any) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Validated read-only copies of the two mean tables, and a label per row."""
    try:
        grade_table = np.array(grade_table_j_per_m, dtype=np.float64, order="C", copy=True)
        turn_table = np.array(turn_table_j, dtype=np.float64, order="C", copy=True)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"grade_table_j_per_m and turn_table_j must be arrays of numbers: {exc}") from exc
    if grade_table.ndim != 2 or grade_table.shape[1] < 3 or grade_table.shape[1] % 2 == 0:
        raise InvalidParameterError(
            f"grade_table_j_per_m must have shape (n_grounds, n_grade) with odd n_grade >= 3, "
            f"got {grade_table.shape!r}"
        )
    n_rows = grade_table.shape[0]
    if turn_table.ndim != 2 or turn_table.shape[0] != n_rows or turn_table.shape[1] < 2:
        raise InvalidParameterError(
            f"turn_table_j must have shape ({n_rows}, n_turn >= 2), got {turn_table.shape!r}"
        )
    labels = tuple(ground_labels) if ground_labels is not None else tuple(f"row{i}" for i in range(n_rows))
    if len(labels) != n_rows:
        raise InvalidParameterError(f"ground_labels needs {n_rows} names, got {labels!r}")
    for tname, tab, allowed in (
        ("grade_table_j_per_m", grade_table, "energies >= 0 or +inf (a grade the ground cannot be driven at)"),
        ("turn_table_j", turn_table, "finite energies >= 0"),
    ):
        bad = np.isnan(tab) | (tab < 0)
        if tname == "turn_table_j":
            bad |= ~np.isfinite(tab)
        if np.any(bad):
            i, j = np.argwhere(bad)[0]
            raise InvalidParameterError(
                f"{tname} must hold {allowed} (minimum-energy planning needs non-negative edge "
                f"costs; a regenerating model must not go below 0), got {tab[i, j]!r} for "
                f"ground {labels[i]!r} at sample {j}"
            )
    for tab in (grade_table, turn_table):
        tab.setflags(write=False)
    return grade_table, turn_table, labels


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

    Planning on a quantile below the median plans on luck: ``risk=1e-9`` priced every edge at
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
    >>> check_planning_risk(0.1)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: risk 0.1 lies below the median: ...
    """
    q = check_risk_level(q, name)
    if q < 0.5:
        raise InvalidParameterError(
            f"{name} {q:g} lies below the median: planning on it assumes the energy comes out lower than it does in "
            f"{100 * (1 - q):.4g} % of runs; give a level in [0.5, 1), e.g. 0.9 (0.5 plans on the mean)", parameter=name)
    return q
