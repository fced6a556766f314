"""Tests of planner.edge_cost: exact cell walks, directional grades, blocking, turns, bounds, and the queries (turn and path energy, surface length, the admissible lower bound, bad points)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from edge_cost_samples import LinearModel, flat_terrain, ramp_terrain, rough_terrain

from energy import PhysicsEnergyModel, ground_preset, robot_preset
from planner import CostTables, EnergyCost, Lattice
from planner.cost_spec import CostSpec
from terrain import GridMismatchError, InvalidParameterError, OutOfBoundsError, TerrainMap, UnknownNameError

GRAVITY_MPS2 = 9.80665


def _reference_energy(cost: EnergyCost, a, b) -> float:
    """Slow reference: TerrainMap.segment_cells + np.interp on the cost's own tables."""
    tmap = cost.terrain
    rows, cols, lengths = tmap.segment_cells(tuple(a), tuple(b))
    if np.any(cost.blocked[rows, cols]):
        return math.inf
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    if length == 0:
        return 0.0
    ux, uy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
    grade = tmap["grad_x"][rows, cols] * ux + tmap["grad_y"][rows, cols] * uy
    grades = np.linspace(-cost.grade_max, cost.grade_max, cost.tables.grade_table_j_per_m.shape[1])
    table_rows = cost.ground_rows[rows, cols]
    per_m = np.array([np.interp(g, grades, cost.tables.grade_table_j_per_m[k]) for g, k in zip(grade, table_rows)])
    return float(np.sum(lengths * per_m))


# --------------------------------------------------------------------------- flat and exactness
def test_flat_uniform_map_energy_proportional_to_length():
    cost = CostSpec(energy_model=LinearModel(a=50.0), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    rng = np.random.default_rng(1)
    a = rng.uniform([0, 0], [30, 20], size=(200, 2))
    b = rng.uniform([0, 0], [30, 20], size=(200, 2))
    e = cost.segment_energy_j(a, b)
    np.testing.assert_allclose(e, 50.0 * np.hypot(*(b - a).T), rtol=1e-12)


def test_segment_energy_matches_reference_walk_on_rough_map():
    tmap = rough_terrain()
    cost = CostSpec(energy_model=LinearModel(), grounds={"a": 1.0, "b": 2.5}, speed_mps=0.5, max_slope_deg=math.degrees(0.6)).build(tmap)
    xmin, ymin, xmax, ymax = tmap.bounds
    rng = np.random.default_rng(2)
    a = rng.uniform([xmin, ymin], [xmax, ymax], size=(150, 2))
    b = rng.uniform([xmin, ymin], [xmax, ymax], size=(150, 2))
    # Ends on grid lines, cell corners and the far map edges too.
    a[:10] = np.round(a[:10] * 2) / 2
    b[10:20] = np.round(b[10:20] * 2) / 2
    b[20:25, 0] = xmax
    a[25:30, 1] = ymax
    got = cost.segment_energy_j(a, b)
    ref = np.array([_reference_energy(cost, p, q) for p, q in zip(a, b)])
    finite = np.isfinite(ref)
    assert finite.sum() > 20 and (~finite).sum() > 5
    np.testing.assert_array_equal(np.isfinite(got[~finite]), np.zeros((~finite).sum(), bool))
    np.testing.assert_allclose(got[finite], ref[finite], rtol=1e-9)
    # The one-segment kernel (OMPL callbacks) agrees with the bulk one.
    one = np.array([cost.segment_energy_one_j(p[0], p[1], q[0], q[1]) for p, q in zip(a, b)])
    np.testing.assert_array_equal(one, got)


def test_zero_length_segment_costs_nothing():
    cost = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    assert cost.segment_energy_j([3.3, 4.4], [3.3, 4.4])[0] == 0.0


# --------------------------------------------------------------------------- direction and slope
def test_uphill_exceeds_downhill_by_gravity_term_closed_form():
    grade, length = 0.1, 30.0
    cost = CostSpec(energy_model=LinearModel(a=50.0, b=400.0), grounds={"asphalt": 1.0}, speed_mps=0.5).build(ramp_terrain(grade))
    up, down = cost.segment_energy_j([[5.0, 10.0], [35.0, 10.0]], [[35.0, 10.0], [5.0, 10.0]])
    factor = math.sqrt(1 + grade**2)  # per metre travelled -> per horizontal metre
    # rel 1e-5: the table interpolates sqrt(1 + s^2) linearly between grade samples.
    assert up == pytest.approx((50.0 + 400.0 * grade) * length * factor, rel=1e-5)
    assert down == pytest.approx(50.0 * length * factor, rel=1e-5)
    assert up - down == pytest.approx(400.0 * grade * length * factor, rel=1e-5)


def test_uphill_exceeds_downhill_by_gravity_term_physics_model():
    grade, length = 0.1, 30.0
    robot = robot_preset("husky")
    model = PhysicsEnergyModel(robot)
    cost = CostSpec(energy_model=model, grounds={"asphalt": ground_preset("asphalt")}, speed_mps=0.5).build(ramp_terrain(grade))
    up, down = cost.segment_energy_j([[5.0, 10.0], [35.0, 10.0]], [[35.0, 10.0], [5.0, 10.0]])
    potential_j = robot.mass_kg * GRAVITY_MPS2 * grade * length
    # The battery pays at least the potential energy going up, and gravity only helps going down.
    assert up - down >= potential_j
    assert up - down < 4.0 * potential_j
    flat = CostSpec(energy_model=model, grounds={"asphalt": ground_preset("asphalt")}, speed_mps=0.5).build(ramp_terrain(0.0))
    e_flat = flat.segment_energy_j([5.0, 10.0], [35.0, 10.0])[0]
    assert up > e_flat and down < up


def test_diagonal_on_ramp_sees_projected_grade():
    grade = 0.2
    cost = CostSpec(energy_model=LinearModel(a=0.0, b=100.0), grounds={"asphalt": 1.0}, speed_mps=0.5).build(ramp_terrain(grade))
    a, b = np.array([5.0, 2.0]), np.array([25.0, 17.0])
    length = float(np.hypot(*(b - a)))
    s = grade * (b[0] - a[0]) / length
    assert cost.segment_energy_j(a, b)[0] == pytest.approx(100.0 * s * length * math.sqrt(1 + s**2), rel=1e-5)
    assert cost.segment_energy_j(b, a)[0] == pytest.approx(0.0, abs=1e-9)


def test_too_steep_cells_are_blocked():
    tmap = ramp_terrain(0.5)  # 26.6 deg
    cost = CostSpec(energy_model=LinearModel(), grounds={"asphalt": 1.0}, speed_mps=0.5, max_slope_deg=20).build(tmap)
    assert cost.blocked.all()
    assert np.isinf(cost.segment_energy_j([1.0, 1.0], [9.0, 9.0])[0])
    relaxed = CostSpec(energy_model=LinearModel(), grounds={"asphalt": 1.0}, speed_mps=0.5, max_slope_deg=30).build(tmap)
    assert np.isfinite(relaxed.segment_energy_j([1.0, 1.0], [9.0, 9.0])[0])


def test_obstacle_blocks_segments_through_it_only():
    obstacle = np.zeros((20, 30), bool)
    obstacle[5:15, 10] = True
    cost = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain(obstacle=obstacle))
    e = cost.segment_energy_j([[2.5, 10.5], [2.5, 17.5]], [[20.5, 10.5], [20.5, 17.5]])
    assert np.isinf(e[0]) and np.isfinite(e[1])
    assert cost.is_free([[10.5, 10.5], [10.5, 17.5]]).tolist() == [False, True]


def test_corner_squeeze_between_diagonal_obstacles_is_blocked():
    obstacle = np.zeros((6, 6), bool)
    obstacle[2, 3] = obstacle[3, 2] = True  # touching only at the corner (3, 3)
    cost = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain(6, 6, obstacle=obstacle))
    # The diagonal from cell (2,2) to (3,3) passes exactly through the shared corner.
    assert np.isinf(cost.segment_energy_j([2.5, 2.5], [3.5, 3.5])[0])
    # One blocked side cell is enough (the robot is not a point); none blocked: free.
    one = obstacle.copy()
    one[3, 2] = False
    cost_one = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain(6, 6, obstacle=one))
    assert np.isinf(cost_one.segment_energy_j([2.5, 2.5], [3.5, 3.5])[0])
    free = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain(6, 6))
    assert free.segment_energy_j([2.5, 2.5], [3.5, 3.5])[0] == pytest.approx(50.0 * math.sqrt(2))


def test_undrivable_grade_blocks_one_direction_only():
    class Steep(LinearModel):
        def energy_per_metre_j(self, speed_mps, grade, ground):
            g = np.asarray(grade, dtype=float)
            return np.where(g > 0.05, np.inf, 50.0)

    cost = CostSpec(energy_model=Steep(), grounds={"asphalt": 1.0}, speed_mps=0.5).build(ramp_terrain(0.1))
    up, down = cost.segment_energy_j([[5.0, 10.0], [35.0, 10.0]], [[35.0, 10.0], [5.0, 10.0]])
    assert np.isinf(up) and np.isfinite(down)
    across = cost.segment_energy_j([10.0, 2.0], [10.0, 18.0])[0]  # along the contour: grade 0
    assert across == pytest.approx(50.0 * 16.0, rel=1e-9)


def test_physics_model_refuses_grades_beyond_the_climbing_limit_so_routes_climb_obliquely():
    """Husky on snow climbs at most ~10 deg at 0.5 m/s (traction); on a 12 deg ramp the fall
    line is impassable uphill but not downhill, and the planner climbs at an angle to it."""
    from planner import plan_route

    model = PhysicsEnergyModel(robot_preset("husky"))
    snow = ground_preset("snow")
    limit = model.max_feasible_grade(0.5, snow)
    grade = math.tan(math.radians(12.0))
    assert limit < grade  # the premise: steeper than the climbing limit, under the 20 deg slope limit
    x = np.arange(40) + 0.5
    tmap = TerrainMap(np.broadcast_to(grade * x, (60, 40)), 1.0, ground=np.zeros((60, 40), int),
                      ground_names={0: "snow"})
    cost = CostSpec(energy_model=model, grounds={"snow": snow}, speed_mps=0.5).build(tmap)
    up, down = cost.segment_energy_j([[5.0, 30.0], [35.0, 30.0]], [[35.0, 30.0], [5.0, 30.0]])
    assert np.isinf(up) and np.isfinite(down)
    route = plan_route(tmap, (5.0, 30.0), (35.0, 30.0), cost=cost, planner="lattice", compare=False)
    assert route.status == "exact"
    seg = np.diff(route.waypoints_m, axis=0)
    along = grade * seg[:, 0] / np.hypot(seg[:, 0], seg[:, 1])  # grade met along each segment
    assert np.all(along <= limit + 1e-9)
    assert route.length_m >= 30.0 * grade / limit * (1 - 1e-6)  # no shorter climb keeps within the limit


def test_speed_above_the_robot_maximum_is_refused():
    model = PhysicsEnergyModel(robot_preset("husky"))
    with pytest.raises(InvalidParameterError, match=r"speed_mps 5\.0 exceeds the robot's max_speed_mps 1\.0"):
        CostSpec(energy_model=model, grounds={"g": ground_preset("asphalt")}, speed_mps=5.0).build(flat_terrain())


# --------------------------------------------------------------------------- construction errors
def test_unknown_ground_class_without_params_raises():
    tmap = rough_terrain()
    with pytest.raises(UnknownNameError, match="'b'"):
        CostSpec(energy_model=LinearModel(), grounds={"a": 1.0}, speed_mps=0.5).build(tmap)


def test_unknown_ground_cells_need_unknown_ground():
    tmap = TerrainMap(np.zeros((10, 10)), 1.0)  # every cell ground -1
    with pytest.raises(InvalidParameterError, match="'gravel' names a ground preset of the physics model"):
        CostSpec(energy_model=LinearModel(), grounds={}, speed_mps=0.5).build(tmap)
    with pytest.raises(InvalidParameterError, match="unknown_ground is None"):
        CostSpec(energy_model=LinearModel(), grounds={}, speed_mps=0.5, unknown_ground=None).build(tmap)
    cost = CostSpec(energy_model=LinearModel(a=50.0), grounds={}, speed_mps=0.5, unknown_ground=2.0).build(tmap)
    assert cost.segment_energy_j([1.0, 1.0], [5.0, 1.0])[0] == pytest.approx(400.0)
    assert cost.tables.ground_labels == ("unknown",)


def test_grounds_keyed_by_class_id():
    cost = CostSpec(energy_model=LinearModel(a=10.0), grounds={0: 1.0, 1: 3.0}, speed_mps=0.5, max_slope_deg=math.degrees(0.6)).build(rough_terrain())
    assert cost.tables.grade_table_j_per_m.shape == (2, 513)
    assert cost.tables.grade_table_j_per_m[1, 256] == pytest.approx(30.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"speed_mps": 0.0}, "speed_mps"),
        ({"speed_mps": math.nan}, "speed_mps"),
        ({"speed_mps": 0.5, "max_slope_deg": 95.0}, "max_slope_deg"),
        ({"speed_mps": "fast"}, "speed_mps must be a real number, got 'fast'"),
        ({"speed_mps": 0.5, "max_slope_deg": "steep"}, "max_slope_deg must be a real number"),
        ({"speed_mps": 0.5, "energy_model": "physics"}, r"energy_model must be an energy.EnergyModel .* got 'str'"),
        ({"speed_mps": 0.5, "grounds": None}, "energy_model needs the ground parameters"),
        ({"speed_mps": 0.5, "grounds": [1.0]}, "grounds must be a mapping"),
    ],
)
def test_a_cost_spec_rejects_bad_parameters(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match) as err:
        CostSpec(**{"energy_model": LinearModel(), "grounds": {"g": 1.0}, **kwargs}).build(flat_terrain())
    assert err.value.parameter is not None


def test_negative_or_nan_model_energy_rejected():
    class Regen(LinearModel):
        def energy_per_metre_j(self, speed_mps, grade, ground):
            return 50.0 + 600.0 * np.asarray(grade, dtype=float)  # negative downhill

    with pytest.raises(InvalidParameterError, match="non-negative"):
        CostSpec(energy_model=Regen(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())

    class Broken(LinearModel):
        def turn_energy_j(self, heading_change_rad, ground):
            return np.full(np.shape(heading_change_rad), np.nan)

    with pytest.raises(InvalidParameterError, match="turn_table_j"):
        CostSpec(energy_model=Broken(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())


def test_a_spec_keeps_its_own_grounds_and_refuses_grounds_beside_a_current_model(known_model):
    grounds = {"g": 1.0}
    spec = CostSpec(energy_model=LinearModel(a=50.0), grounds=grounds, speed_mps=0.5)
    grounds["g"] = 3.0  # the caller's dict changes after the spec was made: the spec's does not
    assert spec.grounds["g"] == 1.0
    assert CostSpec(energy_model=LinearModel(a=50.0), grounds={"g": 1.0}, speed_mps=0.5).build(
        flat_terrain()).tables.grade_table_j_per_m[0, 256] == spec.build(flat_terrain()).tables.grade_table_j_per_m[0, 256]
    with pytest.raises(InvalidParameterError, match="a current model prices the map by its training grounds") as err:
        CostSpec(model=known_model(), grounds={"g": 1.0})
    assert err.value.parameter == "model"


def test_a_model_without_a_robot_takes_the_specs_robots_voltage_and_turn_rate():
    class Bare(LinearModel):
        robot = None

    jackal = robot_preset("jackal")
    cost = CostSpec(robot=jackal, energy_model=Bare(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    assert (cost.battery_voltage_v, cost.turn_rate_radps) == (jackal.battery_voltage_v, jackal.turn_rate_radps)
    own = CostSpec(robot=jackal, energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    assert own.battery_voltage_v == LinearModel.robot.battery_voltage_v != jackal.battery_voltage_v


def test_constructor_checks_grid_and_tables():
    tmap = flat_terrain()
    ok = np.ones((1, 5))
    kw = {"speed_mps": 1.0, "battery_voltage_v": 24.0, "turn_rate_radps": 1.0}
    with pytest.raises(GridMismatchError):
        EnergyCost(tmap, np.zeros((3, 3), int), CostTables(ok, ok), **kw)
    with pytest.raises(InvalidParameterError, match="odd"):
        CostTables(np.ones((1, 4)), ok)
    with pytest.raises(InvalidParameterError, match="ground_rows"):
        EnergyCost(tmap, np.ones((20, 30), int), CostTables(ok, ok), **kw)
    with pytest.raises(InvalidParameterError, match="turn_rate_radps"):
        EnergyCost(tmap, np.zeros((20, 30), int), CostTables(ok, ok), **{**kw, "turn_rate_radps": 0.0})
    with pytest.raises(InvalidParameterError, match="speed_mps must be a real number, got 'fast'"):
        EnergyCost(tmap, np.zeros((20, 30), int), CostTables(ok, ok), **{**kw, "speed_mps": "fast"})
    with pytest.raises(InvalidParameterError, match="grade_table_j_per_m and turn_table_j must be arrays of numbers"):
        CostTables([["a", "b", "c"]], ok)
    with pytest.raises(InvalidParameterError, match="tables must be a CostTables, got 'tuple'") as err:
        EnergyCost(tmap, np.zeros((20, 30), int), (ok, ok), **kw)
    assert err.value.parameter == "tables"
    # Tables are copied and read-only: the caller's arrays stay writable.
    cost = EnergyCost(tmap, np.zeros((20, 30), int), CostTables(ok, ok), **kw)
    assert ok.flags.writeable and not cost.tables.grade_table_j_per_m.flags.writeable


# --------------------------------------------------------------------------- the presets
def _preset_map(names=("asphalt", "grass"), unknown=False):
    ground = np.zeros((12, 16), int)
    ground[:, 8:] = 1
    if unknown:
        ground[0, 0] = -1
    return TerrainMap(np.zeros((12, 16)), 1.0, ground=ground, ground_names=dict(enumerate(names)))


def test_the_presets_equal_their_ground_parameters_given():
    tmap = _preset_map(unknown=True)
    got = CostSpec(speed_mps=0.4, max_slope_deg=15.0).build(tmap)
    ref = CostSpec(grounds={"asphalt": ground_preset("asphalt"), "grass": ground_preset("grass")}, speed_mps=0.4, max_slope_deg=15.0, unknown_ground=ground_preset("gravel")).build(tmap)
    assert got.tables.ground_labels == ref.tables.ground_labels == ("unknown", "asphalt", "grass")
    assert np.array_equal(got.tables.grade_table_j_per_m, ref.tables.grade_table_j_per_m)
    assert np.array_equal(got.tables.turn_table_j, ref.tables.turn_table_j)
    assert np.array_equal(got.ground_rows, ref.ground_rows)


def test_a_spec_on_the_presets_refuses_unknown_names_and_bad_speeds():
    with pytest.raises(UnknownNameError, match=r"named 'lava', which has no preset; known grounds: \[.*'asphalt'"):
        CostSpec().build(_preset_map(("asphalt", "lava")))
    with pytest.raises(InvalidParameterError, match="speed_mps must be a real number, got 'fast'"):
        CostSpec(speed_mps="fast").build(_preset_map())
    with pytest.raises(InvalidParameterError, match="unknown_ground is None"):
        CostSpec(unknown_ground=None).build(_preset_map(unknown=True))
    with pytest.raises(UnknownNameError):
        CostSpec(robot="no such robot").build(_preset_map())
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        CostSpec().build(np.zeros((4, 4)))


# ----------------------------------------------------------------- queries
def test_turn_energies_and_path_energy():
    cost = CostSpec(energy_model=LinearModel(a=50.0, c=30.0), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    pts = np.array([[1.0, 1.0], [11.0, 1.0], [11.0, 1.0], [11.0, 6.0], [6.0, 1.0]])
    angles, turns = cost.turn_energies_j(pts)
    # Repeated point: the 90 degree turn is taken where the new heading starts (index 2).
    np.testing.assert_allclose(angles, [0, 0, math.pi / 2, 3 * math.pi / 4, 0], atol=1e-12)
    np.testing.assert_allclose(turns, 30.0 * angles, rtol=1e-9, atol=1e-12)
    length = 10 + 5 + math.hypot(5, 5)
    assert cost.path_energy_j(pts) == pytest.approx(50.0 * length + 30.0 * (math.pi / 2 + 3 * math.pi / 4), rel=1e-9)


def test_surface_length_on_ramp():
    grade = 0.2
    cost = CostSpec(energy_model=LinearModel(), grounds={"asphalt": 1.0}, speed_mps=0.5).build(ramp_terrain(grade))
    assert cost.surface_length_m([[5.0, 3.0], [25.0, 3.0], [25.0, 13.0]]) == pytest.approx(
        20 * math.sqrt(1 + grade**2) + 10, rel=1e-9
    )


def test_lower_bound_is_admissible():
    tmap = rough_terrain(seed=3, n=40, cell=1.0)
    model = PhysicsEnergyModel(robot_preset("husky"))
    grounds = {"a": ground_preset("asphalt"), "b": ground_preset("grass")}
    cost = CostSpec(energy_model=model, grounds=grounds, speed_mps=0.5, max_slope_deg=math.degrees(0.6)).build(tmap)
    assert cost.min_energy_per_metre_j > 0
    lattice = Lattice(cost)
    rng = np.random.default_rng(4)
    free = np.argwhere(~cost.blocked)
    xs, ys = tmap.cell_centres()
    checked = 0
    for _ in range(25):
        (r0, c0), (r1, c1) = free[rng.choice(len(free), 2, replace=False)]
        a, b = np.array([xs[c0], ys[r0]]), np.array([xs[c1], ys[r1]])
        bound = cost.lower_bound_j(a, b)[0]
        path = lattice.shortest_path(a, b)
        if path.found:
            assert bound <= path.objective * (1 + 1e-12)
            checked += 1
        e = cost.segment_energy_j(a, b)[0]
        assert bound <= e * (1 + 1e-12)
    assert checked >= 10
    # Random (valid) polylines cost at least the bound too.
    pts = rng.uniform([xs[0], ys[0]], [xs[-1], ys[-1]], size=(200, 3, 2))
    for poly in pts:
        e = cost.segment_energy_j(poly[:-1], poly[1:]).sum()
        if np.isfinite(e):
            assert cost.lower_bound_j(poly[0], poly[-1])[0] <= e * (1 + 1e-12)


@pytest.mark.parametrize(
    ("a", "b", "exc", "match"),
    [
        ([[math.nan, 1.0]], [[2.0, 2.0]], InvalidParameterError, "finite"),
        ([[1.0, 1.0]], [[2.0, math.inf]], InvalidParameterError, "finite"),
        ([[1.0, 1.0]], [[31.0, 2.0]], OutOfBoundsError, "outside"),
        ([[1.0, 1.0, 1.0]], [[2.0, 2.0, 2.0]], InvalidParameterError, "shape"),
        ([[1.0, 1.0], [2.0, 2.0]], [[2.0, 2.0]], InvalidParameterError, "equal shapes"),
    ],
)
def test_segment_energy_rejects_bad_points(a, b, exc, match):
    cost = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    with pytest.raises(exc, match=match):
        cost.segment_energy_j(a, b)


@pytest.mark.parametrize("name", ["starts_xy_m", "ends_xy_m"])
def test_segment_energy_names_a_non_numeric_point(name):
    cost = CostSpec(energy_model=LinearModel(), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    points = {"starts_xy_m": [[1.0, 1.0]], "ends_xy_m": [[2.0, 2.0]]}
    points[name] = [["one", "two"]]
    with pytest.raises(InvalidParameterError, match=f"{name} must be a real number or an array of them"):
        cost.segment_energy_j(points["starts_xy_m"], points["ends_xy_m"])


def test_path_spreads_add_each_rows_spreads_linearly_and_reuse_walked_segments() -> None:
    g = np.zeros((4, 20), dtype=int)
    g[:, 10:] = 1
    tmap = TerrainMap(np.zeros((4, 20)), 1.0, ground=g, ground_names={0: "a", 1: "b"})
    tables = CostTables(np.full((2, 5), 10.0), np.zeros((2, 3)), ("a", "b"),
                        grade_sd_table_j_per_m=np.array([[3.0] * 5, [4.0] * 5]),
                        turn_sd_table_j=np.array([[0.0, 1.0, 2.0], [0.0, 0.0, 0.0]]))
    cost = EnergyCost(tmap, g, tables, speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=1.0)
    walked: dict = {}
    straight = cost.path_spreads_j([[2.0, 2.0], [6.0, 2.0], [18.0, 2.0]], segment_cache=walked)
    np.testing.assert_allclose(straight, [8 * 3.0, 8 * 4.0])  # 8 m on a, 8 m on b
    assert set(walked) == {(2.0, 2.0, 6.0, 2.0), (6.0, 2.0, 18.0, 2.0)}
    walked[(2.0, 2.0, 6.0, 2.0)] = np.array([100.0, 0.0])  # a walked segment is not walked again
    assert cost.path_spreads_j([[2.0, 2.0], [6.0, 2.0]], segment_cache=walked).tolist() == [100.0, 0.0]
    turned = cost.path_spreads_j([[2.0, 1.5], [6.0, 1.5], [6.0, 3.5]])  # a right angle on a: half the turn table
    np.testing.assert_allclose(turned, [4 * 3.0 + 2 * 3.0 + 1.0, 0.0])
    plain = EnergyCost(tmap, g, CostTables(np.full((2, 5), 10.0), np.zeros((2, 3))), speed_mps=0.5,
                       battery_voltage_v=24.0, turn_rate_radps=1.0)
    with pytest.raises(InvalidParameterError, match="no standard-deviation tables"):
        plain.path_spreads_j([[2.0, 2.0], [6.0, 2.0]])
