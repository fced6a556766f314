"""The tours' Monte Carlo (planner.tours.check): the share above the reserve beside Q."""

from __future__ import annotations

import numpy as np
from tour_samples import hills_cost  # noqa: F401  (fixture)

from energy import Battery
from planner.tours import TourRobot, TourSearch, TourSites, plan_tour, simulate_tours_mc


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
    robots = [TourRobot(Battery(0.08, 24.0), (20.0, 20.0), f"robot {k}") for k in range(2)]
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
