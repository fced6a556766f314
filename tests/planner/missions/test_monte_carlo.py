"""simulate_missions_mc: reproducible whatever the workers, the reserve risk, the draws, per-mission failures."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from mc_samples import FIXED, NO_DASK, NOMINAL, run_mc, setup  # noqa: F401  (fixture)

from energy import Battery, TruthSimulator, ground_preset, robot_preset
from planner import MissionDistributions, plan_route, simulate_mission, simulate_missions_mc
from planner.cost_spec import CostSpec
from planner.missions import MissionDrive, MissionTruth, MonteCarloStudy
from terrawatt_base.dask_client import Compute
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def test_same_seed_same_missions_and_another_seed_other_missions(setup):
    a, b, c = run_mc(setup, seed=4), run_mc(setup, seed=4), run_mc(setup, seed=5)
    assert np.array_equal(a.energy_j, b.energy_j) and np.array_equal(a.payload_kg, b.payload_kg)
    assert not np.array_equal(a.energy_j, c.energy_j)
    assert a.n == 6 and a.seed == 4 == a.entropy and a.where == "in process"


def test_seed_none_keeps_the_seed_that_repeats_it(setup):
    a = run_mc(setup, n=3, seed=None)
    assert a.seed is None and 0 <= a.entropy < 2**32
    assert np.array_equal(run_mc(setup, n=3, seed=a.entropy).energy_j, a.energy_j)


def test_a_sample_depends_only_on_its_own_seed(setup):
    """Children of one SeedSequence come in spawn order: a longer study extends a shorter one."""
    six, four = run_mc(setup, n=6, seed=9), run_mc(setup, n=4, seed=9)
    assert np.array_equal(six.energy_j[:4], four.energy_j)


def test_percentiles_equal_with_one_and_two_workers(setup):
    distributed = pytest.importorskip("distributed", reason=NO_DASK)
    here = run_mc(setup, n=10, seed=11)
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        one_per_task = run_mc(setup, n=10, seed=11, compute=Compute(client=client, progress=True), chunk_size=1)
        chunks = run_mc(setup, n=10, seed=11, compute=Compute(client=client), chunk_size=4)
    for other in (one_per_task, chunks):
        assert other.energy_percentiles_wh == here.energy_percentiles_wh
        assert np.array_equal(other.energy_j, here.energy_j)
        assert np.array_equal(other.below_reserve, here.below_reserve)
        assert np.array_equal(other.ground_scale, here.ground_scale)
        assert other.n_workers == 2 and other.where == "given client"


def test_fixed_distributions_drive_the_nominal_mission(setup):
    tmap, route = setup
    mc = run_mc(setup, n=3, seed=2, distributions=FIXED)
    assert np.all(mc.payload_kg == 0.0) and np.all(mc.capacity_ah == 2.0) and np.all(mc.ground_scale == 1.0)
    # each sample is simulate_mission with the nominal robot, grounds and battery and the sample's truth seed
    rng = np.random.default_rng(np.random.SeedSequence(2).spawn(3)[0])
    FIXED.draw(rng, ["asphalt"], nominal_speed_mps=0.5)
    truth_seed = int(rng.integers(0, 2**32))
    robot = robot_preset("husky")
    truth = TruthSimulator(robot, {"asphalt": ground_preset("asphalt")}, current_rate_hz=20.0, seed=truth_seed)
    one = simulate_mission(tmap, route, robot, Battery(2.0, 24.0), truth,
                           drive=MissionDrive(speed_mps=mc.speed_mps[0], seed=truth_seed))
    assert mc.energy_j[0] == one.budget.actual_energy_j
    assert mc.arrival_soc[0] == one.budget.arrival_soc


def test_heavier_payload_costs_more_energy(setup):
    light = run_mc(setup, n=3, seed=1, distributions=MissionDistributions(payload_kg=(0.0, 0.0)))
    heavy = run_mc(setup, n=3, seed=1, distributions=MissionDistributions(payload_kg=(60.0, 60.0)))
    assert np.all(heavy.energy_j > light.energy_j)


def test_draws_stay_in_their_ranges(setup):
    d = MissionDistributions(ground_coef_scale=(0.5, 0.6), payload_kg=(5.0, 7.0), capacity_fade_pct=(10.0, 30.0),
                             internal_resistance_ohm=(0.2, 0.3), speed_scale=(0.8, 0.9))
    mc = run_mc(setup, n=8, seed=3, distributions=d)
    assert np.all((mc.ground_scale >= 0.5) & (mc.ground_scale <= 0.6))
    assert np.all((mc.payload_kg >= 5.0) & (mc.payload_kg <= 7.0))
    assert np.all((mc.capacity_ah >= 2.0 * 0.7) & (mc.capacity_ah <= 2.0 * 0.9))
    assert np.all((mc.internal_resistance_ohm >= 0.2) & (mc.internal_resistance_ohm <= 0.3))
    assert np.all((mc.speed_mps >= 0.4) & (mc.speed_mps <= 0.45))


def test_the_reserve_risk_follows_the_battery(setup):
    small = run_mc(setup, n=6, seed=1, battery=Battery(0.05, 24.0))
    large = run_mc(setup, n=6, seed=1, battery=Battery(50.0, 24.0))
    assert small.p_below_reserve == 1.0 and large.p_below_reserve == 0.0
    assert np.all(small.min_soc < 0.2) and np.all(large.min_soc >= 0.2)
    assert np.array_equal(small.below_reserve, small.min_soc < small.battery.reserve_soc)
    lo, hi = large.p_below_reserve_ci95
    assert lo == 0.0 and 0.0 < hi < 0.5  # Wilson: 0 of 6 still leaves room
    assert np.all(np.diff([large.energy_percentile_j(q) for q in (50, 90, 99)]) >= 0)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"n": 0}, InvalidParameterError, "n must be >= 1, got 0"),
        ({"n": -3}, InvalidParameterError, "n must be >= 1"),
        ({"n": 2.5}, InvalidParameterError, "n must be an integer"),
        ({"n": 10**9}, InvalidParameterError, r"n=1000000000 missions: their seeds and results would take .* memory budget .* run at most \d+ missions"),
        ({"n": 10**30}, InvalidParameterError, "more than the memory budget"),
        ({"seed": 2**32}, InvalidParameterError, "seed must be None or an integer"),
        ({"chunk_size": 0}, InvalidParameterError, "chunk_size must be >= 1"),
        ({"current_rate_hz": 0.0}, InvalidParameterError, "current_rate_hz must be > 0"),
        ({"speed_mps": -0.5}, InvalidParameterError, "speed_mps must be > 0"),
        ({"battery": "2 Ah"}, InvalidParameterError, "battery must be a Battery"),
        ({"robot": 3}, InvalidParameterError, "robot must be a RobotParams, a preset name or a robot file"),
        ({"robot": "rover9"}, UnknownNameError, "rover9"),
        ({"grounds": {"sand": ground_preset("sand")}}, UnknownNameError, r"grounds lacks the map's ground\(s\) \['asphalt'\]"),
        ({"distributions": {"payload_kg": (0, 1)}}, InvalidParameterError, "distributions must be a MissionDistributions"),
        ({"compute": {"workers": 2}}, InvalidParameterError, "compute must be a Compute"),
    ],
)
def test_bad_arguments_are_refused(setup, kwargs, error, match):
    args = {"n": 2, "battery": Battery(2.0, 24.0), **kwargs}
    with pytest.raises(error, match=match):
        run_mc(setup, **args)


def test_a_route_that_was_not_found_is_refused(setup):
    tmap, route = setup
    with pytest.raises(InvalidParameterError, match="route must be a found Route, got \"status 'infeasible'\""):
        simulate_missions_mc(tmap, route.replace(status="infeasible", waypoints_m=np.empty((0, 2)),
                                                 segment_energy_j=np.empty(0), turn_energy_j=np.empty(0),
                                                 energy_j=np.nan, length_m=np.nan, duration_s=np.nan), Battery(2, 24),
                             MonteCarloStudy(2))


def test_workers_open_a_local_cluster_through_the_seam(setup, monkeypatch):
    import contextlib

    import terrawatt_base.dask_client as seam

    distributed = pytest.importorskip("distributed", reason=NO_DASK)
    calls = []
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:

        @contextlib.contextmanager
        def fake_dask_client(workers, scheduler, quiet):
            calls.append((workers, scheduler))
            yield client

        monkeypatch.setattr(seam, "dask_client", fake_dask_client)
        mc = run_mc(setup, n=3, seed=1, compute=Compute(workers=2))
    assert calls == [(2, None)] and mc.where == "local cluster" and mc.n_workers == 2
    assert np.array_equal(mc.energy_j, run_mc(setup, n=3, seed=1).energy_j)


def test_a_ground_the_truth_simulator_cannot_drive_is_refused_before_any_mission():
    import terrain

    tmap = terrain.flat_map((10, 20), 1.0, ground="mud")
    cost = CostSpec(grounds={"mud": ground_preset("sand")}, speed_mps=0.5).build(tmap)
    route = plan_route(tmap, (2.5, 2.5), (17.5, 7.5), cost=cost, planner="lattice")
    mud = {"mud": ground_preset("sand").replace(name="mud")}
    with pytest.raises(UnknownNameError, match=r"no vibration signature for ground\(s\) \['mud'\]"):
        simulate_missions_mc(tmap, route, NOMINAL, MonteCarloStudy(3), truth=MissionTruth(grounds=mud))
    with pytest.raises(UnknownNameError, match=r"the map's grounds \['mud'\] have no preset"):
        simulate_missions_mc(tmap, route, NOMINAL, MonteCarloStudy(3))


def test_with_the_planning_cost_the_forecast_prices_the_driven_profile(setup):
    # Without the cost the study compares with the route's edge energy; with it, with the physics forecast of the
    # whole stop-turn-go profile, which the edges price too (their stops, starts and pivot ramps).
    tmap, route = setup
    cost = CostSpec().build(tmap)
    edges = run_mc(setup, n=8, seed=3)
    profile = run_mc(setup, n=8, seed=3, cost=cost)
    assert edges.predicted_energy_j == route.energy_j
    assert profile.predicted_energy_j != route.energy_j
    assert profile.predicted_energy_j == pytest.approx(route.energy_j, rel=0.005)
    np.testing.assert_array_equal(profile.energy_j, edges.energy_j)  # the same missions
    assert "forecast" in profile.summary()


# ------------------------------------------------------------------ per-mission failures
def test_a_failed_mission_is_an_error_row_and_the_others_go_on(setup, tmp_path):
    # a 24 V pack of more than ~1.8 ohm cannot deliver the route's power: those missions fail alone
    d = MissionDistributions(internal_resistance_ohm=(0.0, 4.0))
    mc = run_mc(setup, n=8, seed=1, distributions=d)
    failed = mc.failed
    assert 0 < mc.n_failed < mc.n and mc.n_failed == int(failed.sum())
    assert all("InvalidParameterError: power_w" in e and "maximum deliverable power" in e
               for e in np.asarray(mc.errors)[failed])
    assert not any(np.asarray(mc.errors)[~failed])
    assert np.all(np.isnan(mc.energy_j[failed])) and np.all(np.isfinite(mc.energy_j[~failed]))
    assert not mc.below_reserve[failed].any() and not mc.depleted[failed].any()
    # the failed missions kept their drawn parameters; the failures are the high-resistance draws
    assert np.all(mc.internal_resistance_ohm[failed] > mc.internal_resistance_ohm[~failed].max())
    # statistics over the completed missions
    assert mc.energy_percentile_j(50) == pytest.approx(np.percentile(mc.energy_j[~failed], 50))
    assert mc.p_below_reserve == pytest.approx(np.mean(mc.below_reserve[~failed]))
    assert f"{mc.n_failed} of 8 missions failed" in mc.summary()
    data = mc.to_dict()
    assert data["n_failed"] == mc.n_failed and data["samples"]["error"] == list(mc.errors)
    with open(mc.to_csv(tmp_path / "mc.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    assert [bool(r["error"]) for r in rows] == failed.tolist()
    assert mc.plot(tmp_path / "mc.png").is_file()  # drawn from the completed missions
    # the same rows in the same study, whatever the draws' outcome
    assert np.array_equal(run_mc(setup, n=8, seed=1, distributions=d).failed, failed)


def test_a_study_where_every_mission_fails_reports_nan_statistics(setup):
    mc = run_mc(setup, n=3, seed=1, distributions=MissionDistributions(internal_resistance_ohm=(500.0, 1000.0)))
    assert mc.n_failed == 3 and np.isnan(mc.p_below_reserve) and np.isnan(mc.energy_percentile_j(90))
    assert np.isnan(mc.p_below_reserve_ci95[0]) and "3 of 3 missions failed" in mc.summary()
    with pytest.raises(InvalidParameterError, match="all 3 missions failed"):
        mc.plot("unused.png")


def _dies_on_the_chunk_of(sample, real):
    """A ``run_chunk`` that fails (as a worker that dies would) on the task holding child seed ``sample``."""
    def run_chunk(self, seqs):
        if any(q.spawn_key == (sample,) for q in seqs):
            raise RuntimeError("worker lost")
        return real(self, seqs)
    return run_chunk


def test_a_task_that_fails_is_an_error_row_per_mission_and_the_study_goes_on(setup, monkeypatch):
    """A failed task (a worker that dies, an error outside the library) keeps its missions as failed rows with their
    draws, counted in the result and its summary; the other tasks' missions stand."""
    distributed = pytest.importorskip("distributed", reason=NO_DASK)
    from planner.missions.monte_carlo import MissionSetup

    whole = run_mc(setup, n=6, seed=7, chunk_size=2)
    monkeypatch.setattr(MissionSetup, "run_chunk", _dies_on_the_chunk_of(3, MissionSetup.run_chunk))
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        there = run_mc(setup, n=6, seed=7, chunk_size=2, compute=Compute(client=client))
    here = run_mc(setup, n=6, seed=7, chunk_size=2)
    for mc in (there, here):
        assert mc.failed.tolist() == [False, False, True, True, False, False]  # the task of samples 2 and 3
        assert mc.errors[2] == mc.errors[3] == "RuntimeError: worker lost" and mc.n_failed == 2
        assert np.all(np.isnan(mc.energy_j[2:4])) and not mc.below_reserve[2:4].any()
        keep = ~mc.failed
        assert np.array_equal(mc.energy_j[keep], whole.energy_j[keep])
        # the failed missions' draws are those their seeds give
        for name in ("payload_kg", "capacity_ah", "internal_resistance_ohm", "speed_mps", "ground_scale"):
            assert np.array_equal(getattr(mc, name), getattr(whole, name))
        assert "2 of 6 missions failed" in mc.summary() and "RuntimeError: worker lost" in mc.summary()
        assert mc.to_dict()["n_failed"] == 2 and not mc.ok
        assert mc.energy_percentile_j(50) == pytest.approx(np.percentile(whole.energy_j[keep], 50))


def test_a_task_that_kills_its_workers_fails_its_missions_only(setup):
    """The task of samples 2 and 3 kills each worker process dask retries it on: the study's shared setup is
    computed again on the new workers, the other four missions come back as in process."""
    distributed = pytest.importorskip("distributed", reason=NO_DASK)
    import dask
    from dask_samples import PoisonSample

    whole = run_mc(setup, n=6, seed=7, chunk_size=2)
    with dask.config.set({"distributed.comm.timeouts.connect": "5s"}), distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0"
    ) as cluster, distributed.Client(cluster) as client:
        client.register_plugin(PoisonSample(3))  # on the workers the nannies start too
        there = run_mc(setup, n=6, seed=7, chunk_size=2, compute=Compute(client=client))
    assert there.failed.tolist() == [False, False, True, True, False, False]
    assert there.errors[2] == there.errors[3] and there.errors[2].startswith("KilledWorker") and there.n_failed == 2
    keep = ~there.failed
    assert not whole.failed.any() and np.array_equal(there.energy_j[keep], whole.energy_j[keep])
