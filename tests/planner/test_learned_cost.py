"""Tests of planner.learned_cost: tables equal direct predictions, cached refresh, EnergyCost equality."""

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, PhysicsEnergyModel, ground_preset, robot_preset
from energy.budget import log_battery_power_w
from planner import CostSpec, LearnedEnergyModel
from planner.learned_table import TableProbe
from planner.missions import MissionDrive
from planner.registry import CellModelRegistry
from terrain import InvalidParameterError, TerrainMap, UnknownNameError


class ConstModel:
    """Predicts constant side currents depending only on whether the robot drives or turns."""

    def __init__(self, drive_a: float, turn_a: float) -> None:
        self.drive_a, self.turn_a, self.calls = drive_a, turn_a, 0

    def fit(self, *a, **k):
        return self

    def predict(self, log):
        self.calls += 1
        cur = np.where(np.abs(log.v_mps) > 0, self.drive_a, np.where(np.abs(log.omega_radps) > 0, self.turn_a, 0.0))
        return np.column_stack([cur, cur])


def _setup():
    robot = robot_preset("husky")
    tmap = TerrainMap(np.zeros((12, 16)), 1.0)
    reg = CellModelRegistry.from_terrain(tmap, ConstModel(2.0, 5.0), prior_name="a")
    mid = reg.add_model(ConstModel(4.0, 6.0), name="b")
    reg.assign((np.array([3, 4]), np.array([5, 5])), mid)
    lem = LearnedEnergyModel(reg, robot, ground_preset("asphalt"), probe=TableProbe((0.25, 0.5, 1.0), (0.5, 1.0)))
    return robot, tmap, reg, lem, mid


def test_table_equals_direct_prediction():
    robot, _, reg, lem, mid = _setup()
    tab = lem.table(mid)
    elec = PhysicsEnergyModel(robot, effects=("sensor", "control"))
    for k, v in enumerate((0.25, 0.5, 1.0)):
        n = 50
        log = InteractionLog(np.arange(n) / 100, np.full(n, v), np.zeros(n), np.full(n, 4.0), np.full(n, 4.0),
                             np.arange(n) / 100, np.full(n, 9.81), meta=LogMeta())
        p = log_battery_power_w(log, robot, electronics=False).mean()
        p += float(elec.power(np.array([v]), np.array([0.0]), ground_preset("asphalt")).total_power_w[0])
        assert tab.energy_per_metre_j[k] == pytest.approx(p / v, rel=1e-9)
    assert np.allclose(tab.mean_current_a[:3], 4.0) and np.allclose(tab.mean_current_a[3:], 6.0)
    assert reg.model(mid).calls == 1  # one batched prediction


def test_refresh_only_recomputes_changed_models():
    _, tmap, reg, lem, mid = _setup()
    lem.energy_cost(tmap, 0.5)
    assert lem.table_builds == 2
    lem.energy_cost(tmap, 0.5)
    assert lem.table_builds == 2 and reg.model(0).calls == 1
    new = reg.add_model(ConstModel(8.0, 9.0), name="c")
    reg.assign((np.array([0]), np.array([0])), new)
    lem.energy_cost(tmap, 0.5)
    assert lem.table_builds == 3 and reg.model(0).calls == 1 and reg.model(new).calls == 1


def test_energy_cost_matches_the_spec_on_the_model_id_map():
    _, tmap, reg, lem, mid = _setup()
    fast = lem.energy_cost(tmap, 0.5)
    ids = np.asarray(reg.model_id_map)
    pseudo = TerrainMap(np.zeros(tmap.shape), 1.0, ground=ids, ground_names={0: "a", 1: "b"})
    slow = CostSpec(energy_model=lem, grounds={0: 0, 1: 1}, speed_mps=0.5).build(pseudo)
    np.testing.assert_allclose(fast.tables.grade_table_j_per_m, slow.tables.grade_table_j_per_m, rtol=1e-12)
    np.testing.assert_allclose(fast.tables.turn_table_j, slow.tables.turn_table_j, rtol=1e-12)
    assert np.array_equal(fast.ground_rows, slow.ground_rows)
    # the costlier model's cells cost more
    assert fast.tables.grade_table_j_per_m[1].min() > fast.tables.grade_table_j_per_m[0].min()


def test_slope_term_from_physics():
    robot, _, _, lem, mid = _setup()
    phys = PhysicsEnergyModel(robot)
    g = ground_preset("asphalt")
    e = lem.energy_per_metre_j(0.5, np.array([0.0, 0.1]), mid)
    assert e[1] - e[0] == pytest.approx(float(phys.energy_per_metre_j(0.5, 0.1, g) - phys.energy_per_metre_j(0.5, 0.0, g)))


def test_errors():
    robot, _, reg, lem, _ = _setup()
    with pytest.raises(UnknownNameError, match="no model with id"):
        lem.table(7)
    with pytest.raises(InvalidParameterError, match="speeds_mps"):
        TableProbe(speeds_mps=(0.5, 0.2))
    with pytest.raises(InvalidParameterError, match="probe must be a TableProbe"):
        LearnedEnergyModel(reg, robot, ground_preset("asphalt"), probe={"speeds_mps": (0.5, 1.0)})
    with pytest.raises(InvalidParameterError, match="speed_mps"):
        lem.energy_per_metre_j(0.0, [0.0], 0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"hold_s": "2 s"}, "hold_s must be a real number"),
        ({"rate_hz": 0.0}, "rate_hz must be > 0"),
        ({"settle_s": 2.0}, "settle_s must be < 2"),
        ({"current_convention": "amps"}, r"current_convention must be one of \['motor', 'battery'\]"),
    ],
)
def test_constructor_arguments_are_checked(kwargs, match):
    robot, _, reg, _, _ = _setup()
    if "current_convention" in kwargs:
        with pytest.raises(UnknownNameError, match=match):
            LearnedEnergyModel(reg, robot, ground_preset("asphalt"), **kwargs)
    else:  # the synthetic log's times: the probe's
        with pytest.raises(InvalidParameterError, match=match):
            TableProbe(**kwargs)


def test_energy_cost_and_vibration_arguments_are_named():
    _, tmap, _, lem, mid = _setup()
    with pytest.raises(InvalidParameterError, match="speed_mps must be a real number, got 'fast'"):
        lem.energy_cost(tmap, "fast")
    with pytest.raises(InvalidParameterError, match="grade_samples must be an odd integer"):
        lem.energy_cost(tmap, 0.5, grade_samples=100)
    with pytest.raises(InvalidParameterError, match="accel_time_s must be a real number or an array of them"):
        lem.set_vibration(mid, ["a", "b"], [1.0, 2.0])
    with pytest.raises(InvalidParameterError, match="strictly increasing"):
        lem.set_vibration(mid, [0.0, 0.0, 1.0], [9.8, 9.8, 9.8])
    with pytest.raises(InvalidParameterError, match="accel_z_mps2 has 1 NaN"):
        lem.set_vibration(mid, [0.0, 0.1], [9.8, np.nan])


def test_energy_cost_with_previous_equals_fresh_and_reuses_lattice():
    from planner import Lattice

    robot, tmap, reg, lem, mid = _setup()
    cost = lem.energy_cost(tmap, 0.5)
    lat = Lattice.for_cost(cost, 1)
    new = reg.add_model(ConstModel(8.0, 9.0), name="c")
    reg.assign((np.array([6, 7]), np.array([2, 2])), new)
    got = lem.energy_cost(tmap, 0.5, previous=cost)
    ref = LearnedEnergyModel(reg, robot, ground_preset("asphalt"),
                             probe=TableProbe((0.25, 0.5, 1.0), (0.5, 1.0))).energy_cost(tmap, 0.5)
    assert np.array_equal(got.tables.grade_table_j_per_m, ref.tables.grade_table_j_per_m)
    assert np.array_equal(got.ground_rows, ref.ground_rows)
    assert np.array_equal(got.changed_cells, np.asarray(reg.model_id_map) == new)
    got_lat = Lattice.for_cost(got, 1)
    assert 0 < got_lat.edges_computed < lat.edges_computed
    assert np.array_equal(got_lat._weights("energy"), Lattice(ref, 1)._weights("energy"))
    with pytest.raises(InvalidParameterError, match="previous"):
        lem.energy_cost(tmap, 0.4, previous=cost)


def test_profile_energy_is_the_integral_of_the_cell_models_power():
    # a profile that crosses model b's two cells: each sample priced by the model under it
    from energy import drive_profile

    robot, tmap, reg, lem, mid = _setup()
    profile = drive_profile([[1.5, 3.5], [12.5, 3.5]], 0.5, turn_rate_radps=lem.turn_rate_radps, dt_s=0.01)
    energy = lem.profile_energy_j(tmap, profile)
    pose = np.asarray(profile.pose_xyh)
    rows, cols = tmap.rowcol(pose[:, 0], pose[:, 1])
    ids = np.asarray(reg.model_id_map)[rows, cols]
    assert set(ids.tolist()) == {0, mid}
    t, v, w = profile.time_s, profile.v_mps, profile.omega_radps
    cur = np.where(ids == mid, 4.0, 2.0) * (np.abs(v) > 0)
    log = InteractionLog(t, v, w, cur, cur, t, np.full(t.size, 9.81), meta=LogMeta())
    expected = np.trapezoid(log_battery_power_w(log, robot), t)
    assert energy == pytest.approx(expected, rel=1e-9)
    with pytest.raises(InvalidParameterError, match="poses"):
        lem.profile_energy_j(tmap, type(profile)(t, v, w))


def test_route_prediction_prices_the_stops_the_edge_costs_miss():
    # a model equal to the truth: the profile prediction matches the driven energy, the edge costs do not
    from energy import Battery, LinearCurrentModel, TruthSimulator, excitation_commands
    from planner import simulate_mission
    from planner.route import evaluate_route

    robot = robot_preset("husky")
    truth = TruthSimulator(robot, {"asphalt": ground_preset("asphalt")}, seed=0)
    logs = [truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt", seed=i)
            for i, p in enumerate((
                excitation_commands(30.0, speed_levels_mps=(0.2, 0.5, 0.8), omega_levels_radps=(0.0,), seed=1),
                excitation_commands(12.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
                                    hold_s=(2.0, 3.0), rest_s=0.0, seed=2)))]
    tmap = TerrainMap(np.zeros((20, 30)), 1.0, ground=np.zeros((20, 30), dtype=int), ground_names={0: "asphalt"})
    reg = CellModelRegistry.from_terrain(tmap, LinearCurrentModel().fit(logs), prior_name="asphalt")
    lem = LearnedEnergyModel(reg, robot, ground_preset("asphalt"))
    cost = lem.energy_cost(tmap, 0.5)
    wp = [[2.5, 2.5], [12.5, 2.5], [12.5, 9.5], [20.5, 14.5]]  # two pivots, three stops
    route = evaluate_route(cost, wp)
    actual = simulate_mission(tmap, route, robot, Battery(20.0, 24.0), truth, cost,
                              drive=MissionDrive(seed=5)).budget.actual_energy_j
    predicted = lem.predict_route_energy_j(tmap, wp, 0.5, dt_s=1.0 / truth.current_rate_hz)
    assert abs(predicted / actual - 1.0) < 0.03
    assert abs(route.energy_j / actual - 1.0) > 2 * abs(predicted / actual - 1.0)
    assert predicted > route.energy_j  # stopping and starting costs energy


class _BadLayout(ConstModel):
    """A model whose output layout is not (N, 2): three columns, one column, NaN or too short."""

    def __init__(self, kind: str) -> None:
        super().__init__(3.0, 3.0)
        self.kind = kind

    def predict(self, log):
        good = super().predict(log)
        return {
            "three columns": np.column_stack([good, good[:, :1]]),
            "one column": good[:, 0],
            "nan": np.where(np.arange(len(log))[:, None] == 3, np.nan, good),
            "too short": good[:-1],
        }[self.kind]


@pytest.mark.parametrize("kind", ["three columns", "one column", "nan", "too short"])
def test_models_whose_output_layout_does_not_match_are_refused_by_name(kind):
    from energy import drive_profile
    from planner.missions import validation_error

    robot, tmap, reg, lem, _ = _setup()
    bad = reg.add_model(_BadLayout(kind), name="odd layout")
    reg.assign((np.array([3]), np.array([2])), bad)
    with pytest.raises(InvalidParameterError, match=r"model \d+ \('odd layout'\) must predict finite \(N, 2\)"):
        lem.table(bad)
    profile = drive_profile([[1.5, 3.5], [12.5, 3.5]], 0.5, turn_rate_radps=lem.turn_rate_radps, dt_s=0.01)
    with pytest.raises(InvalidParameterError, match="odd layout"):
        lem.profile_energy_j(tmap, profile)
    t = np.arange(0.0, 5.0, 0.1)
    log = InteractionLog(t, np.full(t.size, 0.5), np.zeros(t.size), np.ones(t.size), np.ones(t.size), t,
                         np.full(t.size, 9.81), meta=LogMeta())
    with pytest.raises(InvalidParameterError, match=r"must predict finite \(N, 2\)"):
        validation_error(reg.model(bad), [log])
