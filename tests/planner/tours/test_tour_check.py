"""The tours' Monte Carlo (planner.tours.check): the share above the reserve beside Q, its JSON and its figure."""

from __future__ import annotations

import numpy as np
import pytest
from tour_samples import hills_cost, with_interval  # noqa: F401  (fixture)

from energy import Battery
from planner.cost_spec import CostSpec
from planner.tours import TourChargers, TourRobot, TourSearch, TourSites, plan_tour, simulate_tours_mc
from terrain import flat_map
from terrawatt_base.errors import InvalidParameterError


def test_monte_carlo_of_the_tours_ends_above_the_reserve_about_as_often_as_q(hills_cost):
    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(12)), rng.uniform(3.0, 37.0, size=(12, 2)))
    robot = TourRobot(Battery(0.15, 24.0), (20.0, 20.0))
    shares = {}
    for q in (0.5, 0.9):
        res = plan_tour(hills_cost, sites, robot, search=TourSearch(risk=q))
        check = simulate_tours_mc(res, 400, seed=2)
        shares[q] = check.share_above_reserve
        assert check.draw_from == "model" and "above the reserve" in check.summary()
    assert shares[0.9] >= 0.88
    assert shares[0.5] < shares[0.9] - 0.1  # the knob means something


def test_every_segment_of_every_tour_runs_on_one_cluster(hills_cost, monkeypatch):
    """A cluster asked for is opened once for the whole check (not once per tour segment), and the draws equal the
    in-process ones."""
    import contextlib

    import pytest

    import terrawatt_base.dask_client as seam
    from terrawatt_base.dask_client import Compute

    distributed = pytest.importorskip("distributed", reason="dask.distributed (the 'distributed' extra) is not installed")
    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(8)), rng.uniform(3.0, 37.0, size=(8, 2)))
    robots = [TourRobot(Battery(0.1, 24.0), (20.0, 20.0), f"robot {k}") for k in range(2)]
    res = plan_tour(hills_cost, sites, robots, search=TourSearch(risk=0.9))
    assert sum(bool(t.legs) for t in res.tours) == 2  # two tours: two studies
    opened = []
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:

        @contextlib.contextmanager
        def fake_dask_client(workers, scheduler, quiet):
            opened.append(workers)
            yield client

        monkeypatch.setattr(seam, "dask_client", fake_dask_client)
        there = simulate_tours_mc(res, 50, seed=1, compute=Compute(workers=2))
    here = simulate_tours_mc(res, 50, seed=1)
    assert opened == [2]
    assert there.share_above_reserve == here.share_above_reserve
    assert all(s.where == "local cluster" for studies in there.runs.values() for s in studies)


def test_a_failed_task_fails_its_tours_counted_in_the_summary_not_dropped(hills_cost, monkeypatch):
    from planner.missions.monte_carlo_model import ModelMissionSetup

    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(6)), rng.uniform(3.0, 37.0, size=(6, 2)))
    res = plan_tour(hills_cost, sites, TourRobot(Battery(0.15, 24.0), (20.0, 20.0)), search=TourSearch(risk=0.9))
    whole = simulate_tours_mc(res, 20, seed=3)
    real = ModelMissionSetup.run_chunk

    def dies_on_the_first_five(self, seqs):  # one study of 20 missions in chunks: fail the missions 0-4
        if any(q.spawn_key[0] < 5 for q in seqs):
            raise RuntimeError("worker lost")
        return real(self, seqs)

    monkeypatch.setattr(ModelMissionSetup, "run_chunk", dies_on_the_first_five)
    check = simulate_tours_mc(res, 20, seed=3)
    (name,) = check.runs
    failed = check.n_failed(name)
    assert failed >= 5 and whole.n_failed(name) == 0
    assert check.above_reserve(name).size == 20 - failed  # the shares are over the completed tours
    assert np.array_equal(check.above_reserve(name), whole.above_reserve(name)[check.completed(name)])
    text = check.summary()
    assert f"of {20 - failed} completed tours" in text and f"{failed} of 20 failed (first: RuntimeError: worker lost)" in text
    assert text.endswith(f"; {failed} tours failed") and "failed" not in whole.summary()


def _charged_corridor():
    """A flat 60 m x 20 m corridor with a spread: a near and a far site, a dock between (the far one needs a charge;
    the battery holds the dock -> far -> dock segment with its U-turn at far)."""
    cost = with_interval(CostSpec().build(flat_map((20, 60), 1.0)))
    sites = TourSites(("near", "far"), [[10.0, 10.0], [55.0, 10.0]], value=[1.0, 5.0])
    robot = TourRobot(Battery(0.12, 24.0, min_reserve_pct=20.0), (2.0, 10.0))
    return plan_tour(cost, sites, robot, chargers=TourChargers(("dock",), [[30.0, 10.0]]),
                     search=TourSearch(risk=0.9, time_limit_s=1.0))


def test_to_dict_is_the_versioned_strict_json_of_the_check_and_write_saves_it(tmp_path):
    import json

    from matplotlib.figure import Figure

    from planner.tours.check import TOUR_CHECK_FORMAT_VERSION
    from terrawatt_base.formats import read_result_json

    res = _charged_corridor()
    tour = res.tours[0]
    assert tour.charging_stops  # the case has segments: a study per segment
    check = simulate_tours_mc(res, 40, seed=1)
    doc = check.to_dict()
    assert doc["format"] == "terrawatt-tour-check" and doc["format_version"] == TOUR_CHECK_FORMAT_VERSION == 1
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc
    assert doc["risk"] == 0.9 and doc["draw_from"] == "model" and doc["n_failed"] == 0
    assert doc["share_above_reserve"] == check.share_above_reserve
    (robot,) = doc["robots"]
    name = tour.robot
    assert robot["robot"] == name and robot["n"] == 40 and robot["n_failed"] == check.n_failed(name) == 0
    assert robot["share_above_reserve"] == check.share_of(name) == check.above_reserve(name).mean()
    assert robot["share_above_at_stops"] == list(check.share_above_at_stops(name))
    # where each segment ends: the charging stops by name, then the depot; one Monte Carlo document per segment
    assert robot["stops"] == [*(tour.stops[k] for k in tour.charging_stops), "depot"]
    assert len(robot["segments"]) == len(tour.charging_stops) + 1 == len(check.runs[name])
    for seg, mc in zip(robot["segments"], check.runs[name]):
        assert seg["format"] == "terrawatt-monte-carlo" and "samples" not in seg
        assert seg["p_below_reserve"] == mc.p_below_reserve and seg["n"] == 40
    ax = Figure().subplots()
    check.plot(ax=ax)  # a bar per segment's end, named as in the JSON
    assert len(ax.patches) == len(robot["stops"]) and [t.get_text() for t in ax.get_xticklabels()] == robot["stops"]
    written = check.write(tmp_path / "out")
    assert [p.name for p in written] == ["tour_check.json", "tour_check.png"]
    assert read_result_json(written[0], "tour-check", TOUR_CHECK_FORMAT_VERSION) == doc


def test_failed_tours_are_counted_in_the_json_and_none_completed_is_null_not_nan(hills_cost, monkeypatch):
    import json

    from planner.missions.monte_carlo_model import ModelMissionSetup

    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(6)), rng.uniform(3.0, 37.0, size=(6, 2)))
    res = plan_tour(hills_cost, sites, TourRobot(Battery(0.15, 24.0), (20.0, 20.0)), search=TourSearch(risk=0.9))
    real = ModelMissionSetup.run_chunk
    dead = {"below": 5}

    def dies_below(self, seqs):  # fail the missions under dead["below"]
        if any(q.spawn_key[0] < dead["below"] for q in seqs):
            raise RuntimeError("worker lost")
        return real(self, seqs)

    monkeypatch.setattr(ModelMissionSetup, "run_chunk", dies_below)
    check = simulate_tours_mc(res, 20, seed=3)
    (name,) = check.runs
    doc = check.to_dict()
    failed = check.n_failed(name)
    assert failed >= 5 and doc["n_failed"] == doc["robots"][0]["n_failed"] == failed
    assert doc["robots"][0]["share_above_reserve"] == check.above_reserve(name).sum() / (20 - failed)
    dead["below"] = 20  # every mission fails: no share to give
    none = simulate_tours_mc(res, 20, seed=3)
    doc = none.to_dict()
    assert none.n_failed(name) == 20 and np.isnan(none.share_above_reserve)
    assert doc["share_above_reserve"] is None and doc["robots"][0]["share_above_at_stops"] == [None]
    json.dumps(doc, allow_nan=False)  # strict JSON


def test_plot_draws_a_bar_per_stop_of_each_robot_beside_q(hills_cost, tmp_path):
    from matplotlib.figure import Figure

    from terrawatt_base.errors import InvalidParameterError

    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(8)), rng.uniform(3.0, 37.0, size=(8, 2)))
    robots = [TourRobot(Battery(0.1, 24.0), (20.0, 20.0), f"robot {k}") for k in range(2)]
    res = plan_tour(hills_cost, sites, robots, search=TourSearch(risk=0.9))
    check = simulate_tours_mc(res, 20, seed=1)
    assert len(check.runs) == 2
    ax = Figure().subplots()
    assert check.plot(ax=ax) is ax
    heights = sorted(100 * s for name in check.runs for s in check.share_above_at_stops(name))
    assert sorted(p.get_height() for p in ax.patches) == heights  # one bar per robot and stop
    assert [t.get_text() for t in ax.get_xticklabels()] == ["depot", "depot"]
    assert [tuple(line.get_ydata()) for line in ax.get_lines()] == [(90.0, 90.0)]  # Q, the reference
    assert all(name in ax.get_legend().get_texts()[k + 1].get_text() for k, name in enumerate(check.runs))
    path = check.plot(tmp_path / "check.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(InvalidParameterError, match="give either path or ax="):
        check.plot(tmp_path / "again.png", ax=ax)


def test_a_check_without_a_tour_says_so_and_writes_only_its_json(tmp_path):
    import json

    from planner.tours import TourCheck
    from terrawatt_base.errors import InvalidParameterError

    empty = TourCheck(0.9, {}, "model")
    assert empty.summary() == "no tour to drive at Q = 0.9: no robot visits a site"
    assert [p.name for p in empty.write(tmp_path)] == ["tour_check.json"]
    doc = json.loads((tmp_path / "tour_check.json").read_text())
    assert doc["robots"] == [] and doc["share_above_reserve"] is None
    with pytest.raises(InvalidParameterError, match="draw_from must be 'model' or 'parameters', got 'truth'"):
        TourCheck(0.9, {}, "truth")
    with pytest.raises(InvalidParameterError, match=r"stops\['r'\] must name the end of each"):
        TourCheck(0.9, {}, "model", stops={"r": ("depot",)})


def test_the_truth_is_the_priced_robot_and_the_draws_are_the_callers(monkeypatch):
    import planner.tours.check as check_module
    from planner.missions import MissionDistributions, MissionTruth

    cost = CostSpec(robot="jackal").build(flat_map((20, 40), 1.0))
    sites = TourSites(("a", "b"), [[10.0, 10.0], [30.0, 10.0]])
    res = plan_tour(cost, sites, TourRobot(Battery(0.15, 12.0), (2.0, 10.0)), search=TourSearch(risk=0.9))
    seen = []
    real = check_module.simulate_missions_mc

    def spy(terrain, route, battery, study, **kw):
        seen.append((study, kw["truth"]))
        return real(terrain, route, battery, study, **kw)

    monkeypatch.setattr(check_module, "simulate_missions_mc", spy)
    fixed = MissionDistributions(payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0))
    check = simulate_tours_mc(res, 8, seed=1, distributions=fixed)
    assert check.draw_from == "parameters" and seen
    assert all(study.distributions is fixed and truth.robot.name == "jackal" for study, truth in seen)
    husky = MissionTruth()
    seen.clear()
    simulate_tours_mc(res, 8, seed=1, truth=husky)
    assert all(truth is husky and study.distributions is None for study, truth in seen)
    with pytest.raises(InvalidParameterError, match="truth"):
        simulate_tours_mc(res, 8, truth="husky")


def test_the_simulated_drive_stops_at_a_site_it_passes_straight_through():
    """A site on the straight line between its neighbours: the plan prices the stop-and-go there (the robot stops to
    serve it), and so does the check's drive (its stops survive the collinear rule): the simulated mean agrees with the
    plan's price as closely as on the tour without that site (the same U-turn at the far end), and the drive lasts
    the stop-and-go longer than the same route driven through."""
    from planner.missions import MissionDistributions, MissionTruth, MonteCarloStudy, simulate_missions_mc

    cost = CostSpec(robot="jackal").build(flat_map((20, 60), 1.0))
    fixed = MissionDistributions(ground_coef_scale=(1.0, 1.0), payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0),
                                 internal_resistance_ohm=(0.0, 0.0), speed_scale=(1.0, 1.0))
    gaps = {}
    for names, xy in ((("mid", "far"), [[25.0, 10.0], [50.0, 10.0]]), (("far",), [[50.0, 10.0]])):
        res = plan_tour(cost, TourSites(names, xy), TourRobot(Battery(0.3, 12.0), (2.0, 10.0)),
                        search=TourSearch(risk=0.9, time_limit_s=1.0))
        tour = res.tours[0]
        assert tour.stops == names
        check = simulate_tours_mc(res, 2, seed=1, distributions=fixed)
        (mc,) = check.runs[tour.robot]
        gaps[names] = float(np.mean(mc.energy_j)) / tour.energy.mean_j - 1.0
        if "mid" in names:
            through = simulate_missions_mc(res.terrain, res.tour_route(0), tour.battery,
                                           MonteCarloStudy(2, seed=1, distributions=fixed),
                                           truth=MissionTruth(robot="jackal"), cost=cost)
            stop_go_j = float(cost.stop_go_at(np.array([0]))[0])
            assert float(np.mean(mc.energy_j - through.energy_j)) == pytest.approx(stop_go_j, rel=0.1)
            assert float(np.mean(mc.duration_s - through.duration_s)) == pytest.approx(1.0, abs=0.1)  # speed / accel
    # driven through, the site's stop-and-go (0.6 % of the tour) would open a gap of that size between the two
    assert gaps[("mid", "far")] == pytest.approx(gaps[("far",)], abs=0.001)
    assert abs(gaps[("far",)]) < 0.005
