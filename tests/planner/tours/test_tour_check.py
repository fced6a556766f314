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
